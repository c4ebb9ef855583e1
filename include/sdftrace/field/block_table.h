// The two-level block table of a sparse grid (not in the papers: Jamriška §3 keeps one flat table
// of blocks; OpenVDB's internal nodes and NanoVDB's flat upper levels make the trade taken here).
// Blocks are grouped into tiles of 8^3 blocks. A tile whose blocks are all outside (all inside)
// shares the constant page 0 (1); every other tile has a page of its own, 512 entries at local
// index (bk & 7) << 6 | (bj & 7) << 3 | (bi & 7). A block's "slot" is page * 512 + local, and the
// per-block tables (flags, sample index, skip distance) are indexed by slot. Memory then follows
// the surface, not the grid's bounding box: an 8192^3 level set around a small surface has 16.7 M
// tiles (84 MiB) where flat tables had 8.6 G blocks (52 GiB at block size 4).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sdftrace/core/macros.h"

namespace sdft {

constexpr int kTileShift = 3;  // log2 of the blocks per tile edge
constexpr int kTileBlocks = 1 << kTileShift;
constexpr int kPageEntries = kTileBlocks * kTileBlocks * kTileBlocks;
constexpr int32_t kOutsidePage = 0, kInsidePage = 1, kFirstOwnPage = 2;

// Index of block (bi, bj, bk) inside its tile's page.
SDFT_HOST_DEVICE inline int pageLocal(int bi, int bj, int bk) {
    return ((bk & (kTileBlocks - 1)) << (2 * kTileShift)) |
           ((bj & (kTileBlocks - 1)) << kTileShift) | (bi & (kTileBlocks - 1));
}

// Calls f(bi, bj, bk) for the blocks of tile (ti, tj, tk) inside a grid of `blocks` blocks, x
// fastest.
template <class F>
void forEachBlockOfTile(const int blocks[3], int ti, int tj, int tk, F&& f) {
    const int hi[3] = {blocks[0] < (ti + 1) * kTileBlocks ? blocks[0] : (ti + 1) * kTileBlocks,
                       blocks[1] < (tj + 1) * kTileBlocks ? blocks[1] : (tj + 1) * kTileBlocks,
                       blocks[2] < (tk + 1) * kTileBlocks ? blocks[2] : (tk + 1) * kTileBlocks};
    for (int bk = tk * kTileBlocks; bk < hi[2]; ++bk)
        for (int bj = tj * kTileBlocks; bj < hi[1]; ++bj)
            for (int bi = ti * kTileBlocks; bi < hi[0]; ++bi) f(bi, bj, bk);
}

// The flags of a sparse grid's blocks in two levels (the builder's input; Grid adds the sample
// indices and skip distances).
struct BlockTable {
    int blocks[3] = {0, 0, 0};      // block grid dimensions
    int tiles[3] = {0, 0, 0};       // tile grid dimensions: ceil(blocks / 8)
    std::vector<int32_t> tilePage;  // per tile, x fastest: its page (own pages in tile order)
    std::vector<uint8_t> flags;     // BlockFlag per slot; pages 0 and 1 are the constant ones

    size_t pages() const { return flags.size() / kPageEntries; }
    size_t tileOf(int bi, int bj, int bk) const {
        return (static_cast<size_t>(bk >> kTileShift) * tiles[1] + (bj >> kTileShift)) * tiles[0] +
               (bi >> kTileShift);
    }
    size_t slot(int bi, int bj, int bk) const {
        return static_cast<size_t>(tilePage[tileOf(bi, bj, bk)]) * kPageEntries +
               pageLocal(bi, bj, bk);
    }
    size_t surfaceBlocks() const;

    // Empty table of `blocks` (every tile on page 0), the constant pages in place.
    static BlockTable empty(const int blocks[3]);
    // From flat per-block flags (x fastest). Throws InputError naming `source` for a wrong count
    // or a flag other than 0, 1, 2.
    static BlockTable fromDense(const int blocks[3], const std::vector<uint8_t>& flags,
                                const std::string& source);
    // Own pages whose blocks (those inside the grid) all have one flag, outside or inside, go back
    // to the constant page; the others are renumbered in tile order.
    void shareConstantPages();
    // The flat per-block flags again (x fastest): what .sdfg files store.
    std::vector<uint8_t> dense() const;
    // Per slot: the index of a surface block's samples when the surface blocks are numbered in
    // flat block order (z, y, x), -1 for the others; `count` the surface blocks (the vector is
    // empty when they are more than 2^31 - 1).
    std::vector<int32_t> surfaceIndices(size_t& count) const;
    // Tiles whose page is their own, in page order: (ti, tj, tk) per page from kFirstOwnPage.
    std::vector<int> ownTiles() const;
};

// The blocks inside the grid by flag.
struct BlockCounts {
    size_t inside = 0, outside = 0, surface = 0;
};
// Of a table given by its parts (BlockTable's, or a Grid's): constant tiles counted by their blocks
// inside the grid, own pages by their flags.
BlockCounts countBlocks(const int blocks[3], const int tiles[3],
                        const std::vector<int32_t>& tilePage, const std::vector<uint8_t>& flags);

}  // namespace sdft
