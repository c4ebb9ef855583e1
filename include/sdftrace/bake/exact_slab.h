// A slab of the sparse exact bake in the form a compressed .sdfg stores it (docs/file-formats.md,
// version 4), so that the ranks of a distributed bake write their parts of one file without any
// rank holding the whole grid (cluster/distributed_bake.h, docs/cluster.md).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "sdftrace/bake/exact_bake.h"

namespace sdft {

struct SlabSections {
    BlockSlab slab;
    std::vector<uint8_t> flags;  // BlockFlag per block of the slab's layers, flat (z, y, x)
    std::vector<float> own;      // per surface block in that order, its B^3 own samples
    // Per surface block, apronWords(B) words: bit a set where apron vertex a is stored explicitly
    // (its owner block is not a surface block, or lies past the grid); the explicit values in
    // `kept`, block after block.
    std::vector<uint64_t> apronMasks;
    std::vector<float> kept;
    size_t surfaceBlocks = 0;
};

// Given the flags of the slab's first block layer, returns the flags of the block layer just past
// the slab (empty where the slab ends the grid): a collective step of the ranks in a distributed
// bake, called once per slab after its phases.
using NextLayerFlags = std::function<std::vector<uint8_t>(const std::vector<uint8_t>& first)>;

// bakeExactSlab's slab as sections: the same samples, split into own samples and aprons as
// saveSdfg's version 4 splits the assembled grid's.
SlabSections bakeExactSlabSections(const TriangleMesh& mesh, const GridShape& shape, int blockSize,
                                   float bandVoxels, SignMethod sign, BlockSlab slab,
                                   const NextLayerFlags& nextLayer, int threads = 0,
                                   ExactBakeStats* stats = nullptr, bool progress = false);

}  // namespace sdft
