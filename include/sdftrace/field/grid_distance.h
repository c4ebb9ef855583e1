// A grid as a distance bound for sphere tracing: the value the tape's grid primitive takes.
#pragma once

#include <cmath>

#include "sdftrace/field/grid.h"

namespace sdft {

// A lower bound of the distance from p, inside the grid's box, to the reconstruction's zero set,
// from the gap lattice (Grid::computeGapLattice): the distance is 1-Lipschitz, so each corner c of
// p's lattice cell bounds it by D(c) - |p - c|; the best of the 8.
SDFT_HOST_DEVICE inline float gapLatticeBound(const GridView& g, Vec3 p) {
    const float step = static_cast<float>(g.gapStep) * g.shape.voxelSize;
    const Vec3 l = (p - g.shape.origin) * (1.0f / step);
    const int i = clampi(static_cast<int>(std::floor(l.x)), 0, g.gapCounts[0] - 2);
    const int j = clampi(static_cast<int>(std::floor(l.y)), 0, g.gapCounts[1] - 2);
    const int k = clampi(static_cast<int>(std::floor(l.z)), 0, g.gapCounts[2] - 2);
    const size_t sx = 1, sy = static_cast<size_t>(g.gapCounts[0]),
                 sz = sy * static_cast<size_t>(g.gapCounts[1]);
    const size_t base =
        static_cast<size_t>(k) * sz + static_cast<size_t>(j) * sy + static_cast<size_t>(i);
    float best = 0;
    for (int c = 0; c < 8; ++c) {
        const int dx = c & 1, dy = c >> 1 & 1, dz = c >> 2;
        const Vec3 d = l - Vec3(static_cast<float>(i + dx), static_cast<float>(j + dy),
                                static_cast<float>(k + dz));
        const float at =
            static_cast<float>(g.gapLattice[base + dx * sx + dy * sy + dz * sz]) * g.gapUnit;
        best = maxf(best, at - std::sqrt(dot(d, d)) * step);
    }
    return best;
}

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
// the gap where samples give it. Where the grid has a gap lattice (a narrow band in a scene), the
// blocks without samples and the samples the band's clamp may hold down read the larger of that
// and gapLatticeBound, so that within a block or so of the surface the bound follows the surface
// rather than the band's width: SDF soft shadows (k h / t) no longer read the clamp as a near miss.
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
    float f;  // the bound at q
    if (data >= 0) {
        float c[8];
        g.blockCellCorners(data, i - (bi << sh), j - (bj << sh), k - (bk << sh), c);
        f = trilinear(c, u, v, w) / lipschitz;
        // Where clamped samples may hold the value down, the gap lattice may know better.
        if (g.gapLattice && std::fabs(f) * lipschitz >= 0.5f * g.background) {
            const float gap = gapLatticeBound(g, q);
            if (gap > std::fabs(f)) f = f < 0 ? -gap : gap;
        }
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
        if (g.gapLattice) gap = maxf(gap, gapLatticeBound(g, q));
        const float d = maxf(gap, g.background / lipschitz);
        f = inside ? -d : d;
    }
    if (out2 == 0.0f) return f;
    // |p - s|^2 >= |p - q|^2 + |q - s|^2 for any s in the box (q projects p onto it), and
    // |q - s| >= f: the bound stays at least the distance to the box, as bounds culling and
    // SDF soft shadows assume (dividing the whole root by L fell below it wherever L > 1).
    const float outside = maxf(f, 0.0f);
    return std::sqrt(out2 + outside * outside);
}

}  // namespace sdft
