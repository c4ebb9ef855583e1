// On-disk form of a sparse grid's surface blocks without the samples they share: each block keeps
// its (B+1)^3 vertices in memory (Jamriška §3), but the B^3 it owns are enough on disk where the
// neighbour that owns the rest (the +x, +y, +z faces, edges and corner: the block's "apron") is a
// surface block holding the same value. Aprons that differ or whose owner stores nothing are kept
// explicitly, flagged in a bit mask per block, so the split is lossless for any grid.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sdftrace/field/block_table.h"
#include "sdftrace/field/grid.h"

namespace sdft {

struct SplitBlocks {
    std::vector<float> own;         // B^3 per surface block, x fastest, in block order
    std::vector<uint64_t> masks;    // per surface block, apronWords() words: bit = kept explicitly
    std::vector<float> explicitly;  // the kept apron samples, block by block, in apron order
};

// Apron positions per block ((B+1)^3 - B^3) and the mask words they take.
int apronSize(int blockSize);
int apronWords(int blockSize);

SplitBlocks splitBlocks(const Grid& grid);

// The surface blocks' (B+1)^3 samples again, the blocks numbered in flat block order (z, y, x)
// as in the grid. Throws InputError naming `source` when the masks, the explicit samples and the
// flags do not fit together (an implicit apron whose owner is not a surface block, a wrong count).
// Nothing is sized by the grid's bounding box but what `table` holds (its tiles).
std::vector<float> joinBlocks(const GridShape& shape, int blockSize, const BlockTable& table,
                              const SplitBlocks& split, const std::string& source);

}  // namespace sdft
