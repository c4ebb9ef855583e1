// The exact mesh SDF on a grid: the distance to the closest point of the mesh (Embree BVH point
// queries) with the sign by the generalized winding number (or ray-crossing parity). The ground
// truth the other bake methods are measured against.
//
// Two things keep it fast without approximating anything:
//  - along a grid row each query searches only within the distance to the previous vertex's
//    closest point (a point of the mesh, so a bound of this distance);
//  - on a watertight mesh the sign can only change where the surface passes between two
//    neighbours, so the winding number is evaluated only where d < h (and once per row);
//    elsewhere the neighbour's sign is exact. Open meshes evaluate it at every sample.
// The sparse bake computes only the narrow band, by scattering each triangle to the vertices within
// the band of its bounds (a vertex closer than the band to the mesh is within the band of its
// closest triangle's bounds, so the minimum is exact there); samples beyond the band are clamped to
// it (decision 0003). Only surface blocks' vertices are signed; on a watertight mesh the integer
// winding number is carried between neighbours through the signed crossings of the segment between
// them. It gives the same grid as sparsifying the dense bake.
#pragma once

#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/bake/sign_method.h"
#include "sdftrace/field/grid.h"

namespace sdft {

struct ExactBakeStats {
    size_t distanceQueries = 0;  // dense: BVH queries; sparse: vertices found within the band
    size_t signEvaluations = 0;  // winding numbers or parity votes actually computed
    size_t surfaceBlocks = 0;    // sparse: blocks in the band
};

// Every vertex of `shape` (x fastest). `progress`: a percentage on stderr (when it is a terminal).
std::vector<float> bakeExactSamples(const MeshBvh& bvh, const GridShape& shape, SignMethod sign,
                                    int threads = 0, ExactBakeStats* stats = nullptr,
                                    bool progress = false);

// A sparse block grid sampling only the narrow band (equal to Grid::sparseFromDense of
// bakeExactSamples with the same block size and band).
Grid bakeExactSparse(const MeshBvh& bvh, const GridShape& shape, int blockSize, float bandVoxels,
                     SignMethod sign, int threads = 0, ExactBakeStats* stats = nullptr,
                     bool progress = false);

}  // namespace sdft
