// The way back from a field to a mesh: the isosurface of a grid as triangles, by OpenVDB's
// volumeToMesh (dual contouring with an adaptive merge of coplanar regions). Triangles wind
// counter-clockwise seen from outside (the positive side), so normals point out.
#pragma once

#include <string>

#include "sdftrace/bake/triangle_mesh.h"
#include "sdftrace/field/grid.h"

namespace sdft {

struct ExtractOptions {
    float isovalue = 0;    // world units: 0 is the surface, > 0 an offset surface outside it
    float adaptivity = 0;  // [0, 1]: 0 keeps every voxel's polygon, 1 merges the most
};

struct ExtractStats {
    size_t quads = 0, triangles = 0;  // as volumeToMesh made them (each quad becomes two triangles)
    double convertSeconds = 0, contourSeconds = 0;
};

// Throws InputError naming `source` when the isovalue lies outside the grid's stored band (no
// reliable surface there) or the grid has no surface at it.
TriangleMesh extractSurface(const Grid& grid, const ExtractOptions& options,
                            const std::string& source, ExtractStats* stats = nullptr);

}  // namespace sdft
