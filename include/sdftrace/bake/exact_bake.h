// The exact mesh SDF on a grid: the distance to the closest point of the mesh (Embree BVH point
// queries) with the sign by the generalized winding number (or ray-crossing parity). The ground
// truth the other bake methods are measured against.
#pragma once

#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/field/grid.h"
#include "sdftrace/field/sample_grid.h"

namespace sdft {

enum class SignMethod {
    WindingNumber,  // generalized winding number > 1/2 (robust on open meshes; the default)
    RayParity,      // majority of three ray-crossing parities (closed meshes only)
};

std::vector<float> bakeExactSamples(const MeshBvh& bvh, const GridShape& shape, SignMethod sign,
                                    int threads = 0);

// The grid over the mesh's bounds as SampleOptions asks (resolution, layout, band, padding).
Grid bakeMeshExact(const TriangleMesh& mesh, const SampleOptions& options,
                   SignMethod sign = SignMethod::WindingNumber);

}  // namespace sdft
