#include "sdftrace/field/block_table.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>

#include "sdftrace/core/error.h"
#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/field/grid.h"

namespace sdft {

namespace {
constexpr uint8_t kOutside = static_cast<uint8_t>(BlockFlag::Outside);
constexpr uint8_t kInside = static_cast<uint8_t>(BlockFlag::Inside);
constexpr uint8_t kSurface = static_cast<uint8_t>(BlockFlag::Surface);
}  // namespace

BlockTable BlockTable::empty(const int blocks[3]) {
    BlockTable t;
    for (int a = 0; a < 3; ++a) {
        t.blocks[a] = blocks[a];
        t.tiles[a] = (blocks[a] + kTileBlocks - 1) >> kTileShift;
    }
    t.tilePage.assign(static_cast<size_t>(t.tiles[0]) * t.tiles[1] * t.tiles[2], kOutsidePage);
    t.flags.assign(2 * kPageEntries, kOutside);
    std::fill(t.flags.begin() + kPageEntries, t.flags.end(), kInside);
    return t;
}

size_t BlockTable::surfaceBlocks() const {
    return static_cast<size_t>(
        std::count(flags.begin() + kFirstOwnPage * kPageEntries, flags.end(), kSurface));
}

BlockCounts countBlocks(const int blocks[3], const int tiles[3],
                        const std::vector<int32_t>& tilePage, const std::vector<uint8_t>& flags) {
    BlockCounts n;
    for (size_t tile = 0; tile < tilePage.size(); ++tile) {
        const int t[3] = {static_cast<int>(tile % tiles[0]),
                          static_cast<int>(tile / tiles[0] % tiles[1]),
                          static_cast<int>(tile / (static_cast<size_t>(tiles[0]) * tiles[1]))};
        const int32_t page = tilePage[tile];
        if (page < kFirstOwnPage) {
            size_t inTile = 1;
            for (int a = 0; a < 3; ++a)
                inTile *= static_cast<size_t>(std::min(blocks[a], (t[a] + 1) * kTileBlocks) -
                                              t[a] * kTileBlocks);
            (page == kInsidePage ? n.inside : n.outside) += inTile;
            continue;
        }
        const uint8_t* f = flags.data() + static_cast<size_t>(page) * kPageEntries;
        forEachBlockOfTile(blocks, t[0], t[1], t[2], [&](int bi, int bj, int bk) {
            const uint8_t flag = f[pageLocal(bi, bj, bk)];
            if (flag == static_cast<uint8_t>(BlockFlag::Inside))
                ++n.inside;
            else if (flag == static_cast<uint8_t>(BlockFlag::Outside))
                ++n.outside;
            else
                ++n.surface;
        });
    }
    return n;
}

BlockTable BlockTable::fromDense(const int blocks[3], const std::vector<uint8_t>& dense,
                                 const std::string& source) {
    BlockTable t = empty(blocks);
    const size_t numBlocks = static_cast<size_t>(blocks[0]) * blocks[1] * blocks[2];
    if (dense.size() != numBlocks)
        throw InputError(source + ": block flag count does not match the grid size");
    // Every tile on a page of its own first (a copy of the flags, as large as `dense`), then the
    // tiles of one flag back on the constant pages.
    const size_t numTiles = t.tilePage.size();
    for (size_t tile = 0; tile < numTiles; ++tile)
        t.tilePage[tile] = kFirstOwnPage + static_cast<int32_t>(tile);
    t.flags.resize((kFirstOwnPage + numTiles) * kPageEntries, kOutside);
    const std::vector<int> own = t.ownTiles();
    std::atomic<bool> invalid{false};
    tbb::parallel_for(size_t(0), own.size() / 3, [&](size_t p) {
        uint8_t* page = t.flags.data() + (p + kFirstOwnPage) * kPageEntries;
        forEachBlockOfTile(
            blocks, own[3 * p], own[3 * p + 1], own[3 * p + 2], [&](int bi, int bj, int bk) {
                const uint8_t f =
                    dense[(static_cast<size_t>(bk) * blocks[1] + bj) * blocks[0] + bi];
                if (f > kSurface) invalid = true;
                page[pageLocal(bi, bj, bk)] = f;
            });
    });
    if (invalid) {
        for (size_t b = 0; b < numBlocks; ++b)
            if (dense[b] > kSurface)
                throw InputError(source + ": block " + std::to_string(b) + " has an invalid flag " +
                                 std::to_string(dense[b]) +
                                 " (accepted: 0 outside, 1 inside, 2 surface)");
    }
    t.shareConstantPages();
    return t;
}

void BlockTable::shareConstantPages() {
    const std::vector<int> own = ownTiles();
    const size_t n = own.size() / 3;
    std::vector<int32_t> becomes(n);  // kOutsidePage, kInsidePage or kFirstOwnPage (kept)
    tbb::parallel_for(size_t(0), n, [&](size_t p) {
        const uint8_t* page = flags.data() + (p + kFirstOwnPage) * kPageEntries;
        bool anyOut = false, anyIn = false, other = false;
        forEachBlockOfTile(blocks, own[3 * p], own[3 * p + 1], own[3 * p + 2],
                           [&](int bi, int bj, int bk) {
                               const uint8_t f = page[pageLocal(bi, bj, bk)];
                               anyOut |= f == kOutside;
                               anyIn |= f == kInside;
                               other |= f > kInside;
                           });
        becomes[p] = (other || (anyOut && anyIn)) ? kFirstOwnPage
                     : anyIn                      ? kInsidePage
                                                  : kOutsidePage;
    });
    int32_t next = kFirstOwnPage;
    for (size_t p = 0; p < n; ++p) {
        const size_t tile =
            (static_cast<size_t>(own[3 * p + 2]) * tiles[1] + own[3 * p + 1]) * tiles[0] +
            own[3 * p];
        if (becomes[p] != kFirstOwnPage) {
            tilePage[tile] = becomes[p];
            continue;
        }
        // Pages only move down, in order: a copy never overwrites a page still to be read.
        if (static_cast<size_t>(next) != p + kFirstOwnPage)
            std::copy_n(
                flags.begin() + static_cast<std::ptrdiff_t>((p + kFirstOwnPage) * kPageEntries),
                kPageEntries, flags.begin() + static_cast<std::ptrdiff_t>(next) * kPageEntries);
        tilePage[tile] = next++;
    }
    flags.resize(static_cast<size_t>(next) * kPageEntries);
    flags.shrink_to_fit();
}

std::vector<uint8_t> BlockTable::dense() const {
    std::vector<uint8_t> out(static_cast<size_t>(blocks[0]) * blocks[1] * blocks[2]);
    tbb::parallel_for(0, blocks[2], [&](int bk) {
        for (int bj = 0; bj < blocks[1]; ++bj)
            for (int bi = 0; bi < blocks[0]; ++bi)
                out[(static_cast<size_t>(bk) * blocks[1] + bj) * blocks[0] + bi] =
                    flags[slot(bi, bj, bk)];
    });
    return out;
}

std::vector<int32_t> BlockTable::surfaceIndices(size_t& count) const {
    // Per row of blocks, the own tiles of its row of tiles (in page order, which is tile order)
    // left to right; rows counted per z slab in parallel, then numbered from each slab's start.
    const std::vector<int> own = ownTiles();
    const size_t tileRows = static_cast<size_t>(tiles[1]) * tiles[2];
    std::vector<size_t> rowStart(tileRows + 1, 0);  // own pages before each row of tiles
    for (size_t p = 0; p * 3 < own.size(); ++p)
        ++rowStart[static_cast<size_t>(own[3 * p + 2]) * tiles[1] + own[3 * p + 1] + 1];
    for (size_t r = 0; r < tileRows; ++r) rowStart[r + 1] += rowStart[r];
    const int nz = blocks[2], ny = blocks[1], nx = blocks[0];
    auto forSlab = [&](int bk, auto&& visit) {
        for (int bj = 0; bj < ny; ++bj) {
            const size_t row =
                static_cast<size_t>(bk >> kTileShift) * tiles[1] + (bj >> kTileShift);
            for (size_t p = rowStart[row]; p < rowStart[row + 1]; ++p) {
                const int ti = own[3 * p];
                const size_t page = (p + kFirstOwnPage) * kPageEntries;
                for (int bi = ti * kTileBlocks; bi < std::min(nx, (ti + 1) * kTileBlocks); ++bi) {
                    const size_t slot = page + pageLocal(bi, bj, bk);
                    if (flags[slot] == kSurface) visit(slot);
                }
            }
        }
    };
    std::vector<size_t> slabStart(static_cast<size_t>(nz) + 1, 0);
    tbb::parallel_for(0, nz, [&](int bk) {
        size_t n = 0;
        forSlab(bk, [&](size_t) { ++n; });
        slabStart[static_cast<size_t>(bk) + 1] = n;
    });
    for (int bk = 0; bk < nz; ++bk) slabStart[bk + 1] += slabStart[bk];
    count = slabStart[static_cast<size_t>(nz)];
    if (count > static_cast<size_t>(INT32_MAX)) return {};
    std::vector<int32_t> index;
    assignHuge(index, flags.size(), int32_t{-1});
    tbb::parallel_for(0, nz, [&](int bk) {
        auto next = static_cast<int32_t>(slabStart[static_cast<size_t>(bk)]);
        forSlab(bk, [&](size_t slot) { index[slot] = next++; });
    });
    return index;
}

std::vector<int> BlockTable::ownTiles() const {
    std::vector<int> out((pages() > kFirstOwnPage ? pages() - kFirstOwnPage : 0) * 3);
    for (size_t tile = 0; tile < tilePage.size(); ++tile) {
        const int32_t page = tilePage[tile];
        if (page < kFirstOwnPage) continue;
        int* o = out.data() + static_cast<size_t>(page - kFirstOwnPage) * 3;
        o[0] = static_cast<int>(tile % tiles[0]);
        o[1] = static_cast<int>(tile / tiles[0] % tiles[1]);
        o[2] = static_cast<int>(tile / (static_cast<size_t>(tiles[0]) * tiles[1]));
    }
    return out;
}

}  // namespace sdft
