// A grid as a distance bound for sphere tracing: the value the tape's grid primitive takes.
#pragma once

#include <cmath>

#include "sdftrace/field/grid.h"

namespace sdft {

// The grid primitive's value: GridView::sample over the grid's Lipschitz bound L (so that it is
// 1-Lipschitz like the primitives; a sparse grid's L is its block's, Grid::computeLocalLipschitz),
// except in sparse blocks without samples. There +-background / L
// is raised to the gap to the nearest block holding a sign-changing cell, which is where the
// reconstruction's zero set lies: a block at Chebyshev block distance d (blockSkip) from every such
// block is at least (d - 1) B h away from them, a block of a constant tile at tile distance d
// (tileSkip) at least ((d - 1) 8 + m) B h, m its blocks to the tile's nearest face
// that another tile lies beyond. Without it the whole non-band part of a grid's box reads
// +-background / L, a few voxels: sphere tracing crawls through it in steps of that size, and a
// screen-space hit test (Keinert §3.2) takes any of it seen from farther than that over the pixel
// radius for the surface (a box around a mesh in a scene). Outside the box the bound is
// sqrt(|p - q|^2 + gap^2) through the nearest box point q, as in GridView::sample, with f / L for
// the gap where samples give it.
SDFT_HOST_DEVICE inline float gridDistanceBound(const GridView& g, Vec3 p) {
    const Vec3 hi = g.shape.origin + Vec3(static_cast<float>(g.shape.cells[0]),
                                          static_cast<float>(g.shape.cells[1]),
                                          static_cast<float>(g.shape.cells[2])) *
                                         g.shape.voxelSize;
    const Vec3 q = min(max(p, g.shape.origin), hi);
    const Vec3 d = p - q;
    const float out2 = dot(d, d);
    if (g.kind != GridKind::Sparse || !g.blockSkip || !g.tileSkip) {
        if (out2 == 0.0f) return g.sample(p) / g.lipschitz;
        const float outside = maxf(g.sample(q), 0.0f) / g.lipschitz;
        return std::sqrt(out2 + outside * outside);
    }
    // GridView::sample's steps, with the block looked up once for the gap and the samples.
    int i, j, k;
    float u, v, w;
    g.locate(q, i, j, k, u, v, w);
    const int sh = g.blockShift(), bi = i >> sh, bj = j >> sh, bk = k >> sh;
    const size_t tile = g.tileIndex(bi, bj, bk);
    const int32_t page = g.tilePage[tile];
    const size_t slot = static_cast<size_t>(page) * kPageEntries + pageLocal(bi, bj, bk);
    // The block's or the tile's bound where the grid has them (Grid::computeLocalLipschitz).
    const float lipschitz = !g.tileLipschitz
                                ? g.lipschitz
                                : g.lipschitzLevel[page < kFirstOwnPage ? g.tileLipschitz[tile]
                                                                        : g.blockLipschitz[slot]];
    const int32_t data = g.blockData[slot];
    float f;
    if (data >= 0) {
        float c[8];
        g.blockCellCorners(data, i - (bi << sh), j - (bj << sh), k - (bk << sh), c);
        f = trilinear(c, u, v, w);
    } else {
        const bool inside = g.flags[slot] == static_cast<uint8_t>(BlockFlag::Inside);
        const float blockSide = static_cast<float>(g.blockSize) * g.shape.voxelSize;
        float gap;
        if (page < kFirstOwnPage) {
            // The nearest such block lies in a tile at least tileSkip tiles away, past this
            // tile's nearest face.
            int inner = kTileBlocks;  // faces on the grid's boundary lead to no tile
            const int b[3] = {bi, bj, bk};
            for (int a = 0; a < 3; ++a) {
                const int local = b[a] & (kTileBlocks - 1), t = b[a] >> kTileShift;
                if (t > 0 && local < inner) inner = local;
                if (t + 1 < g.tiles[a] && kTileBlocks - 1 - local < inner)
                    inner = kTileBlocks - 1 - local;
            }
            gap = static_cast<float>((g.tileSkip[tile] - 1) * kTileBlocks + inner) * blockSide;
        } else {
            gap = static_cast<float>(static_cast<int>(g.blockSkip[slot]) - 1) * blockSide;
        }
        if (gap > g.background / lipschitz) {
            if (inside) return out2 == 0.0f ? -gap : std::sqrt(out2);
            return std::sqrt(out2 + gap * gap);
        }
        f = inside ? -g.background : g.background;
    }
    if (out2 == 0.0f) return f / lipschitz;
    // |p - s|^2 >= |p - q|^2 + |q - s|^2 for any s in the box (q projects p onto it), and
    // |q - s| >= f / L: the bound stays at least the distance to the box, as bounds culling and
    // SDF soft shadows assume (dividing the whole root by L fell below it wherever L > 1).
    const float outside = maxf(f, 0.0f) / lipschitz;
    return std::sqrt(out2 + outside * outside);
}

}  // namespace sdft
