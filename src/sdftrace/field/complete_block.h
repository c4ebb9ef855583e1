// One block of a complete block grid (Grid::completeFromDense: every block holds samples, as
// RTSDF's per-frame grids do) refreshed from a dense field: the kernel body of the refresh, run by
// Grid::refreshComplete on the CPU and by the GPU's refresh (gpu/gpu_complete_grid.cu), one block
// per call. The layout stays; the samples, cell masks and gradient bound are the block's anew.
#pragma once

#include <cstddef>
#include <cstdint>

#include "sdftrace/field/block_masks.h"
#include "sdftrace/field/grid.h"

namespace sdft {

// Grid::sparseFromDense's clamp of a sample to +-band: std::fmin's values (a NaN sample gives the
// band), without its call.
SDFT_HOST_DEVICE inline float clampToBand(float s, float band) {
    return s < 0 ? -(-s < band ? -s : band) : (s < band ? s : band);
}

// What a refresh reads and writes (plain pointers: host or device arrays alike).
struct CompleteRefreshView {
    GridShape shape;
    int blocks[3] = {0, 0, 0};
    float band = 0;                           // stored samples are clamped to +-band (world units)
    const float* dense = nullptr;             // shape.vertexCount() samples, x fastest
    const int32_t* blockNeighbors = nullptr;  // GridView::blockNeighbors (the layout's)
    int32_t surfaceBlocks = 0;                // = blocks; sample blocks past them are aprons
    float* blockSamples = nullptr;            // written: own samples and private aprons
    uint64_t* cellMasks = nullptr;            // written: the block's words
    float* worst = nullptr;                   // written: per block, its largest
                                              // cellGradientBound2 (times h^2)
};

// Block `data` (its flat index (bk by + bj) bx + bi: a complete grid numbers its blocks so): its
// (B+1)^3 vertices read from the dense field (clamped to the grid at its far faces, and to the
// band, as Grid::sparseFromDense reads them), its B^3 own samples and its private apron entries
// written, its cell masks and gradient bound computed (block_masks.h). Apron entries held by a
// neighbour block are that block's own samples, written by its call.
template <int B>
SDFT_HOST_DEVICE inline void refreshCompleteBlock(const CompleteRefreshView& v, int32_t data) {
    constexpr int V = B + 1;
    constexpr size_t own = static_cast<size_t>(B) * B * B;
    const int bx = v.blocks[0], by = v.blocks[1];
    const int bi = data % bx, bj = (data / bx) % by, bk = data / bx / by;
    const int n[3] = {v.shape.cells[0], v.shape.cells[1], v.shape.cells[2]};
    const size_t vx = static_cast<size_t>(n[0]) + 1, vy = static_cast<size_t>(n[1]) + 1;
    const int32_t* nb = v.blockNeighbors + static_cast<size_t>(data) * 8;
    float e[V * V * V];
    for (int z = 0; z <= B; ++z) {
        const int gz = bk * B + z < n[2] ? bk * B + z : n[2];
        for (int y = 0; y <= B; ++y) {
            const int gy = bj * B + y < n[1] ? bj * B + y : n[1];
            const float* row = v.dense + (static_cast<size_t>(gz) * vy + gy) * vx;
            for (int x = 0; x <= B; ++x) {
                const int gx = bi * B + x < n[0] ? bi * B + x : n[0];
                const float s = row[gx];
                const float c = clampToBand(s, v.band);
                e[(z * V + y) * V + x] = c;
                const int code = (x == B) | (y == B) << 1 | (z == B) << 2;
                const size_t local =
                    (static_cast<size_t>(z % B) * B + static_cast<size_t>(y % B)) * B + x % B;
                if (code == 0)
                    v.blockSamples[static_cast<size_t>(data) * own + local] = c;
                else if (nb[code] >= v.surfaceBlocks)  // a private apron block
                    v.blockSamples[static_cast<size_t>(nb[code]) * own + local] = c;
            }
        }
    }
    const int ni = n[0] - bi * B < B ? n[0] - bi * B : B;
    const int nj = n[1] - bj * B < B ? n[1] - bj * B : B;
    const int nk = n[2] - bk * B < B ? n[2] - bk * B : B;
    constexpr int words = (B * B * B + 63) / 64;
    uint64_t* mask = v.cellMasks + static_cast<size_t>(data) * words;
    for (int w = 0; w < words; ++w) mask[w] = 0;
    v.worst[data] = blockMasksAndBoundOf<B>(e, ni, nj, nk, mask);
}

}  // namespace sdft
