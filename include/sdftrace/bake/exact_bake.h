// The exact mesh SDF on a grid: the distance to the closest point of the mesh (Embree BVH point
// queries) with the sign by ray-crossing parity. The ground truth the other bake methods are
// measured against.
#pragma once

#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/field/grid.h"
#include "sdftrace/field/sample_grid.h"

namespace sdft {

std::vector<float> bakeExactSamples(const MeshBvh& bvh, const GridShape& shape, int threads = 0);

// The grid over the mesh's bounds as SampleOptions asks (resolution, layout, band, padding).
Grid bakeMeshExact(const TriangleMesh& mesh, const SampleOptions& options);

}  // namespace sdft
