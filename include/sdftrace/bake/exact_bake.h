// The exact mesh SDF on a grid: the distance to the closest point of the mesh (Embree BVH point
// queries) with the sign by the generalized winding number (or ray-crossing parity). The ground
// truth the other bake methods are measured against.
//
// Three things keep it fast without approximating anything:
//  - the dense bake's distances come from the closest point transform (closest_point_transform.h):
//    each face's, edge's and vertex's region is scan-converted once instead of a BVH search per
//    vertex. The BVH path (ClosestPoints::Bvh) stays as the baseline it is measured against:
//    along a grid row each query searches only within the distance to the previous vertex's
//    closest point (a point of the mesh, so a bound of this distance);
//  - signs are carried from sample to sample (closing_film.h): the mesh's boundary is closed by
//    small films, so the winding number W of mesh + films is an integer that changes only by the
//    signed crossings of a segment between neighbours (none where one of them is farther than a
//    voxel from the mesh). The mesh's own winding number is W less the films', carried with an
//    error bound from the rim's Biot-Savart integral and summed over the films where that error
//    reaches 1/2. On a watertight mesh there are no films. The hierarchical winding number is
//    evaluated only where no neighbour can vouch.
// The sparse bake computes only the narrow band, by scattering each triangle to the vertices within
// the band of its bounds (a vertex closer than the band to the mesh is within the band of its
// closest triangle's bounds, so the minimum is exact there); samples beyond the band are clamped to
// it (decision 0003). Only surface blocks' vertices are signed one by one; the other blocks take
// the sign of their centre, carried along block rows. It gives the same grid as sparsifying the
// dense bake, and needs no BVH (but for parity signs).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sdftrace/bake/bake_stage.h"
#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/bake/sign_method.h"
#include "sdftrace/field/grid.h"

namespace sdft {

// How the dense bake finds distances.
enum class ClosestPoints {
    Transform,  // scan-converted feature regions (closest_point_transform.h); the default
    Bvh,        // an Embree point query per vertex
};
const char* closestPointsName(ClosestPoints c);  // "transform", "bvh"
bool parseClosestPoints(const std::string& name, ClosestPoints& out);

struct ExactBakeStats {
    size_t distanceQueries = 0;  // dense: BVH queries; sparse: vertices found within the band
    size_t transformRows = 0, transformEvaluations = 0;  // dense, ClosestPoints::Transform
    size_t signEvaluations = 0;  // winding numbers or parity votes computed from scratch
    size_t filmSums =
        0;  // open meshes: sums over the closing films where a carried sign was unsure
    size_t surfaceBlocks = 0;       // sparse: blocks in the band
    std::vector<BakeStage> phases;  // its phases
};

// Every vertex of `shape` (x fastest). `progress`: a percentage on stderr (when it is a terminal).
std::vector<float> bakeExactSamples(const MeshBvh& bvh, const GridShape& shape, SignMethod sign,
                                    int threads = 0, ExactBakeStats* stats = nullptr,
                                    bool progress = false,
                                    ClosestPoints closest = ClosestPoints::Transform);

// A sparse block grid sampling only the narrow band (equal to Grid::sparseFromDense of
// bakeExactSamples with the same block size and band).
Grid bakeExactSparse(const TriangleMesh& mesh, const GridShape& shape, int blockSize,
                     float bandVoxels, SignMethod sign, int threads = 0,
                     ExactBakeStats* stats = nullptr, bool progress = false);

// A slab of a sparse exact bake: the block layers [first, last) along z (cluster/distributed_bake.h
// deals them to the ranks of a job). last = 0: the whole grid.
struct BlockSlab {
    int first = 0, last = 0;
};
struct SlabSamples {
    BlockSlab slab;
    std::vector<uint8_t> flags;  // BlockFlag per block of the slab's layers, flat (z, y, x)
    std::vector<float> samples;  // per surface block in that order, its (B+1)^3 vertex samples
};

// The slab's blocks of bakeExactSparse(mesh, shape, ...): each its flag, and the surface blocks'
// samples, bit for bit those of the whole bake. The work and the arrays are the slab's (plus a
// block layer on each side): only the triangles that come within the band of the slab are
// scattered; signs evaluated from scratch use the whole mesh's winding number.
SlabSamples bakeExactSlab(const TriangleMesh& mesh, const GridShape& shape, int blockSize,
                          float bandVoxels, SignMethod sign, BlockSlab slab, int threads = 0,
                          ExactBakeStats* stats = nullptr, bool progress = false);

// The sparse grid of slabs that cover the grid's block layers in order: bakeExactSparse's.
Grid assembleExactSlabs(const GridShape& shape, int blockSize, float bandVoxels,
                        const std::vector<const SlabSamples*>& slabs, int threads = 0);

}  // namespace sdft
