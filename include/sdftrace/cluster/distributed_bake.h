// The sparse exact mesh bake across the job's ranks (docs/cluster.md): the grid's block layers
// cut into one slab per rank, balanced by the triangles that reach each layer; each rank bakes its
// slab (the triangles within the band of it, the whole mesh's winding number for signs, arrays the
// slab's size). A .sdfg output is written by every rank, its slab's part (bakeExactToSdfg); other
// outputs, and bakes that read the whole grid afterwards (--verify, --texcoords), have rank 0
// assemble the slabs into the grid (bakeExactAcross). Both are the single-process bake's samples,
// bit for bit.
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

// `count` slabs or fewer, each at least one tile layer (8 block layers) and starting on a tile
// layer, covering the grid's layers in order and balanced as balancedSlabs balances them: the
// slabs whose parts of a .sdfg's sections follow each other (bakeExactToSdfg).
std::vector<BlockSlab> tileSlabs(const TriangleMesh& mesh, const GridShape& shape, int blockSize,
                                 float bandVoxels, int count);

// What rank 0 reports of a bake written by every rank.
struct DistributedBakeSummary {
    GridShape shape;
    uint64_t surface = 0, inside = 0, outside = 0;
    uint64_t fileBytes = 0;
    double peakMiB = 0;  // the largest peak resident memory of any rank
    std::vector<BakeStage> stages;
    std::string details;
};

// Every rank: the sparse exact bake of `mesh` written straight into one .sdfg (version 4) at
// `path` by all ranks, no rank holding the whole grid. Rank r bakes slab r of tileSlabs (ranks
// past the slabs bake nothing), splits it into the file's sections, and writes its chunks with
// MPI-IO at offsets agreed from every rank's sizes (a chunk that straddles two ranks' parts is
// compressed by the rank holding its first byte, the rest sent to it). Rank 0 writes the header
// and chunk table, under a temporary name renamed into place when every rank has written. Any
// rank's error ends the job on every rank (RankFailure) with no file left.
DistributedBakeSummary bakeExactToSdfg(Communicator& comm, const TriangleMesh& mesh,
                                       const MeshBakeOptions& options, const std::string& path,
                                       int level);

// Rank 0: bakeMesh(mesh, options) for an exact sparse bake, on every rank of the farm. Stages:
// the slowest rank's slab (rank 0's phases), the gather and the assembly.
MeshBakeResult bakeExactAcross(WorkFarm& farm, const TriangleMesh& mesh,
                               const MeshBakeOptions& options);

// The other ranks' side: bakes the slabs rank 0 deals (the mesh and options as rank 0's).
std::unique_ptr<RoundWorker> exactSlabWorker(const TriangleMesh& mesh,
                                             const MeshBakeOptions& options, const Bytes& context);

}  // namespace sdft
