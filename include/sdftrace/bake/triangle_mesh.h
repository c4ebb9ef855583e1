// The triangle mesh the bakers take: positions and index triples (loaded and cleaned by
// io/mesh_io.h, or built in memory).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "sdftrace/math/ray.h"

namespace sdft {

struct TriangleMesh {
    std::vector<Vec3> positions;
    std::vector<std::array<uint32_t, 3>> triangles;

    Bounds3 bounds() const;
};

// Every directed edge (a, b) is matched by as many (b, a): the mesh bounds closed regions, so its
// winding number is an integer, constant between crossings of the surface.
bool isWatertight(const TriangleMesh& mesh);

}  // namespace sdft
