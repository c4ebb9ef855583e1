// A complete block grid's empty-space skip distances (Grid::computeBlockSkip's) as Chebyshev
// dilations, one entry per thread: the GPU's refresh (gpu/gpu_complete_grid.cu) runs these
// functions as its kernels' bodies, and CompleteGrid.SkipDistancesByDilation holds them to
// computeBlockSkip on the CPU. Blocks are addressed in the tile grid's extent ("padded": tiles x 8
// blocks per axis), as every tile of a complete grid has a page of its own whose 512 entries all
// take a distance, those past the grid's blocks included.
#pragma once

#include <cstddef>
#include <cstdint>

#include "sdftrace/field/grid.h"

namespace sdft {

constexpr uint8_t kSkipFarBlocks = kTileBlocks + 1;  // computeBlockSkip's "beyond 8"
constexpr uint16_t kSkipFarTiles = 256;              // its tile transform's start

// The slot of padded block (x, y, z) of a complete grid.
SDFT_HOST_DEVICE inline size_t completePaddedSlot(const GridView& g, int x, int y, int z) {
    return static_cast<size_t>(g.tilePage[g.tileIndex(x, y, z)]) * kPageEntries +
           pageLocal(x, y, z);
}

// A dilation's start at padded block (x, y, z): 0 for a block holding a sign-changing cell (a set
// bit in its cell mask), else far.
SDFT_HOST_DEVICE inline uint8_t blockSkipSource(const GridView& g, int x, int y, int z) {
    if (x >= g.blocks[0] || y >= g.blocks[1] || z >= g.blocks[2]) return kSkipFarBlocks;
    const int32_t data = g.blockData[completePaddedSlot(g, x, y, z)];
    if (data < 0) return kSkipFarBlocks;
    const int words = g.wordsPerMask();
    const uint64_t* mask = g.cellMasks + static_cast<size_t>(data) * words;
    for (int w = 0; w < words; ++w)
        if (mask[w] != 0) return 0;
    return kSkipFarBlocks;
}

// One step of a Chebyshev distance transform of an nx x ny x nz array (x fastest) at (x, y, z):
// the least of the entry and its 26 neighbours' plus one. k steps from sources at 0 and far
// entries elsewhere give min(far, distance) wherever the distance is at most k.
template <class T>
SDFT_HOST_DEVICE inline T chebyshevStep(const T* in, int nx, int ny, int nz, int x, int y, int z) {
    unsigned m = in[(static_cast<size_t>(z) * ny + y) * nx + x];
    for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const int a = x + dx, b = y + dy, c = z + dz;
                if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) continue;
                const unsigned v = in[(static_cast<size_t>(c) * ny + b) * nx + a] + 1u;
                m = v < m ? v : m;
            }
    return static_cast<T>(m);
}

// The tile transform's start at tile (tx, ty, tz): 0 when one of its blocks is a source (0 in the
// padded block distances d, px x py blocks per z layer), else far.
SDFT_HOST_DEVICE inline uint16_t tileSkipSource(const uint8_t* d, int px, int py, int tx, int ty,
                                                int tz) {
    for (int z = 0; z < kTileBlocks; ++z)
        for (int y = 0; y < kTileBlocks; ++y)
            for (int x = 0; x < kTileBlocks; ++x)
                if (d[(static_cast<size_t>(tz * kTileBlocks + z) * py + ty * kTileBlocks + y) * px +
                      tx * kTileBlocks + x] == 0)
                    return 0;
    return kSkipFarTiles;
}

// A tile distance as GridView::tileSkip stores it (capped at 255).
SDFT_HOST_DEVICE inline uint8_t tileSkipEntry(uint16_t d) {
    return static_cast<uint8_t>(d < 255 ? d : 255);
}

}  // namespace sdft
