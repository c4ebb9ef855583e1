// On-disk form of a sparse grid's surface blocks without the samples they share: each block's
// cells read (B+1)^3 vertices (Jamriška §3), but the B^3 it owns are enough on disk where the
// neighbour that owns the rest (the +x, +y, +z faces, edges and corner: the block's "apron") is a
// surface block holding the same value. Aprons that differ or whose owner stores nothing are kept
// explicitly, flagged in a bit mask per block, so the split is lossless for any grid. The own
// samples are the grid's own buffer as it is (decision 10): files write them from it and loaders
// decompress them straight into the builder's, so neither side copies the grid.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "sdftrace/field/block_apron_layout.h"  // apronSize, apronWords, apronPositions
#include "sdftrace/field/grid.h"
#include "sdftrace/field/sparse_grid_builder.h"

namespace sdft {

struct ApronSamples {
    std::vector<uint64_t> masks;    // per surface block, apronWords() words: bit = kept explicitly
    std::vector<float> explicitly;  // the kept apron samples, block by block, in apron order
};

// The aprons of a sparse grid's surface blocks; their own samples are the first
// surfaceBlockCount() * B^3 of grid.blockSamples().
ApronSamples splitAprons(const Grid& grid);

// The grid again from a builder whose ownSamples() hold every surface block's own samples: each
// block's apron read from its neighbours' own samples or the kept ones, its cells' masks and
// bounds computed, blocks in parallel. The kept samples come from `read(from, to)` (a pointer to
// samples [from, to), valid until the next call; released before the grid's tables are made),
// asked for windows of at most `window` samples
// in block order, so a loader decompresses them piece by piece and never holds them all. Throws
// InputError naming `source` when the masks, the kept samples and the table do not fit together
// (an implicit apron whose owner is not a surface block, a wrong count) or a sample is not
// finite.
using KeptApronReader = std::function<const float*(uint64_t from, uint64_t to)>;
Grid joinAprons(SparseGridBuilder& builder, std::vector<uint64_t> masks, uint64_t keptCount,
                KeptApronReader read, uint64_t window, const std::string& source);
// The same from aprons in memory.
Grid joinAprons(SparseGridBuilder& builder, const ApronSamples& aprons, const std::string& source);

}  // namespace sdft
