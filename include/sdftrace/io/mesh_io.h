// Triangle meshes from files: PLY, STL and OFF by sdftrace's own readers, which hold every count a
// file declares to its size (a file cut short or damaged is one error, never a crash), the other
// formats (OBJ, glTF/GLB, ...) through assimp with its scene validated; cleaned the way real scans
// need: exactly-duplicate vertices welded, degenerate and zero-area triangles
// dropped, and what was found reported (duplicate and opposite-winding triangles, open boundary
// edges, components). An unreadable, empty or non-finite mesh is an InputError naming the file.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "sdftrace/bake/triangle_mesh.h"
#include "sdftrace/math/ray.h"

namespace sdft {

struct MeshReport {
    size_t verticesRead = 0, trianglesRead = 0;  // as the importer delivers them (OBJ: per corner)
    size_t weldedVertices = 0;       // records merged into another with the exact same position
    size_t unusedVertices = 0;       // dropped: referenced by no triangle
    size_t degenerateTriangles = 0;  // dropped: repeated vertex or zero area
    size_t duplicateTriangles = 0;   // kept: same vertices, same or opposite winding
    size_t boundaryEdges = 0;        // edges used by one triangle (an open mesh)
    size_t components = 0;           // edge-connected pieces

    std::string summary() const;  // one line for stderr
};

TriangleMesh loadMesh(const std::string& path, MeshReport* report = nullptr);

// The cleaning loadMesh applies, for meshes built in memory.
TriangleMesh cleanMesh(const std::vector<Vec3>& positions,
                       const std::vector<std::array<uint32_t, 3>>& triangles, MeshReport& report);

}  // namespace sdft
