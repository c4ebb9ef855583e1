// A surface block's cell masks (Jamriška 2010, §4.1: one bit per cell whose 8 corner samples
// differ in sign, the cells that contain the surface) and its cells' largest squared gradient
// bound (Liktor 2008, §2.2: the Lipschitz bound of the trilinear reconstruction), in one pass over
// the block's (B+1)^3 vertex samples. Shared by the sparse grid builder, the refresh of complete
// block grids (complete_grid.h) and its GPU kernel.
#pragma once

#include <cmath>
#include <cstdint>

#include "sdftrace/core/macros.h"

namespace sdft {

// The cells of a row of a block that change sign, one bit per cell (the first ni), from the
// negative-vertex bits of the row's 4 corner rows of vertices: some corner of cell i (bits i and
// i + 1) is negative and not all are.
SDFT_HOST_DEVICE inline uint32_t rowSignChanges(uint32_t a, uint32_t b, uint32_t c, uint32_t d,
                                                int ni) {
    const uint32_t any = a | b | c | d, all = a & b & c & d;
    return ((any | any >> 1) & ~(all & all >> 1)) & ((1u << ni) - 1);
}

// std::max's choice (b only when a < b), on the host and the device.
SDFT_HOST_DEVICE inline float maxOfFloats(float a, float b) { return a < b ? b : a; }

// One surface block's cell masks (or-ed into `mask`, (B^3 + 63) / 64 words) and the largest
// cellGradientBound2 over its first ni x nj x nk cells, from its (B+1)^3 vertex samples `s`
// (x fastest). The same values as cell by cell, computed once per vertex and edge rather than once
// per cell corner (each edge is shared by four cells), in fixed-size rows the compiler vectorizes.
template <int B>
SDFT_HOST_DEVICE inline float blockMasksAndBoundOf(const float* s, int ni, int nj, int nk,
                                                   uint64_t* mask) {
    constexpr int V = B + 1, sy = V, sz = V * V;
    // Edge differences, in straight rows.
    float ex[V][V][B], ey[V][B][V], ez[B][V][V];
    for (int k = 0; k < V; ++k)
        for (int j = 0; j < V; ++j) {
            const float* r = s + k * sz + j * sy;
            for (int i = 0; i < B; ++i) ex[k][j][i] = std::fabs(r[i + 1] - r[i]);
            if (j < B)
                for (int i = 0; i < V; ++i) ey[k][j][i] = std::fabs(r[i + sy] - r[i]);
            if (k < B)
                for (int i = 0; i < V; ++i) ez[k][j][i] = std::fabs(r[i + sz] - r[i]);
        }
    // Vertex signs, one bit per x along each (j, k) row.
    uint32_t negative[V][V];
    for (int k = 0; k < V; ++k)
        for (int j = 0; j < V; ++j) {
            const float* r = s + k * sz + j * sy;
            uint32_t bits = 0;
            for (int i = 0; i < V; ++i) bits |= static_cast<uint32_t>(r[i] < 0) << i;
            negative[k][j] = bits;
        }
    // Cells past ni (a block cut by the grid's face) count for neither.
    float keep[B];
    for (int i = 0; i < B; ++i) keep[i] = i < ni ? 1.0f : 0.0f;
    float worst = 0;
    for (int k = 0; k < nk; ++k)
        for (int j = 0; j < nj; ++j) {
            // cellGradientBound2 of each cell of the row: its 4 x-, y- and z-edges' largest.
            float rowWorst = 0;
            for (int i = 0; i < B; ++i) {
                const float gx = maxOfFloats(maxOfFloats(ex[k][j][i], ex[k][j + 1][i]),
                                             maxOfFloats(ex[k + 1][j][i], ex[k + 1][j + 1][i]));
                const float gy = maxOfFloats(maxOfFloats(ey[k][j][i], ey[k][j][i + 1]),
                                             maxOfFloats(ey[k + 1][j][i], ey[k + 1][j][i + 1]));
                const float gz = maxOfFloats(maxOfFloats(ez[k][j][i], ez[k][j][i + 1]),
                                             maxOfFloats(ez[k][j + 1][i], ez[k][j + 1][i + 1]));
                rowWorst = maxOfFloats(rowWorst, (gx * gx + gy * gy + gz * gz) * keep[i]);
            }
            worst = maxOfFloats(worst, rowWorst);
            const uint32_t change = rowSignChanges(negative[k][j], negative[k][j + 1],
                                                   negative[k + 1][j], negative[k + 1][j + 1], ni);
            const int bit = (k * B + j) * B;
            mask[bit / 64] |= static_cast<uint64_t>(change) << (bit % 64);
        }
    return worst;
}

}  // namespace sdft
