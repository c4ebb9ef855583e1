// The sparse exact mesh bake across the job's ranks (docs/cluster.md): the grid's block layers cut
// into one slab per rank, balanced by the triangles that reach each layer; each rank bakes its
// slab (bakeExactSlab: the triangles within the band of it, the whole mesh's winding number for
// signs, arrays the slab's size) and rank 0 assembles the slabs into the grid, bit for bit the
// single-process bake.
#pragma once

#include <memory>
#include <vector>

#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/cluster/work_farm.h"

namespace sdft {

// `count` slabs covering the block layers [0, ceil(cells_z / B)) in order, each with about the same
// number of triangle-layer overlaps (within the band) plus layers; some are empty when there are
// fewer layers than slabs.
std::vector<BlockSlab> balancedSlabs(const TriangleMesh& mesh, const GridShape& shape,
                                     int blockSize, float bandVoxels, int count);

// Rank 0: bakeMesh(mesh, options) for an exact sparse bake, on every rank of the farm. Stages:
// the slowest rank's slab (rank 0's phases), the gather and the assembly.
MeshBakeResult bakeExactAcross(WorkFarm& farm, const TriangleMesh& mesh,
                               const MeshBakeOptions& options);

// The other ranks' side: bakes the slabs rank 0 deals (the mesh and options as rank 0's).
std::unique_ptr<RoundWorker> exactSlabWorker(const TriangleMesh& mesh,
                                             const MeshBakeOptions& options, const Bytes& context);

}  // namespace sdft
