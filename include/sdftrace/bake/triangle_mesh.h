// The triangle mesh the bakers take: positions and index triples (loaded and cleaned by
// io/mesh_io.h, or built in memory).
#pragma once

#include <array>
#include <cstdint>
#include <string>
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

// The coordinates the bakers compute with in float: |x| <= kMaxMeshCoordinate (squared and
// multiplied distances stay finite), a bounding box at least kMinMeshExtent across, and no
// farther from the origin than kMaxMeshOffset times its size (float keeps about 7 digits, so a
// small mesh far away loses its shape to rounding at a voxel's scale).
inline constexpr float kMaxMeshCoordinate = kMaxCoordinate;
inline constexpr float kMinMeshExtent = 1e-9f;
inline constexpr float kMaxMeshOffset = 1e4f;
// Why the mesh (the vertices its triangles use) is outside that range, in one sentence that says
// what works; empty when inside.
std::string meshRangeProblem(const TriangleMesh& mesh);

}  // namespace sdft
