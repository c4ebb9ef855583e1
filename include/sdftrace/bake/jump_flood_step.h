// One vertex of one jump-flooding pass (Tan et al. 2022, RTSDF §2.2; Rong and Tan 2006), the body
// the CPU's parallel sweep (jump_flood.cpp) and the GPU's one thread per vertex
// (gpu/gpu_bake.cu) both run: the vertex adopts the nearest of the seed points held by itself and
// its 26 neighbours at the pass's offset.
#pragma once

#include <cstddef>

#include "sdftrace/field/grid.h"

namespace sdft {

constexpr float kNoSeed = 1e30f;  // x of a vertex that holds no point

// Vertex (i, j, k) of `shape`, x fastest.
SDFT_HOST_DEVICE inline size_t vertexIndex(const GridShape& s, int i, int j, int k) {
    return (static_cast<size_t>(k) * s.vertices(1) + j) * s.vertices(0) + i;
}
SDFT_HOST_DEVICE inline Vec3 vertexPosition(const GridShape& s, int i, int j, int k) {
    return s.origin +
           Vec3(static_cast<float>(i), static_cast<float>(j), static_cast<float>(k)) * s.voxelSize;
}

// f(jj, kk) for each row of vertices at the pass's `offset` around row (j, k) (itself included)
// that lies in the grid, z then y ascending: the order in which a vertex meets its candidates.
template <class F>
SDFT_HOST_DEVICE inline void forEachJumpRow(const GridShape& s, int j, int k, int offset, F&& f) {
    for (int dk = -offset; dk <= offset; dk += offset) {
        const int kk = k + dk;
        if (kk < 0 || kk >= s.vertices(2)) continue;
        for (int dj = -offset; dj <= offset; dj += offset) {
            const int jj = j + dj;
            if (jj >= 0 && jj < s.vertices(1)) f(jj, kk);
        }
    }
}

// The closest point vertex (i, j, k) holds after the pass at `offset` over `seed` (kNoSeed in x:
// none). Ties keep the first found: the vertex's own, then its neighbours with z, y, x ascending.
SDFT_HOST_DEVICE inline Vec3 jumpFloodVertex(const GridShape& s, const Vec3* seed, int i, int j,
                                             int k, int offset) {
    const int vx = s.vertices(0);
    const Vec3 p = vertexPosition(s, i, j, k);
    Vec3 best = seed[vertexIndex(s, i, j, k)];
    float bestD = best.x == kNoSeed ? kNoSeed : dot(p - best, p - best);
    forEachJumpRow(s, j, k, offset, [&](int jj, int kk) {
        for (int di = -offset; di <= offset; di += offset) {
            const int ii = i + di;
            if (ii < 0 || ii >= vx) continue;
            const Vec3 q = seed[vertexIndex(s, ii, jj, kk)];
            if (q.x == kNoSeed) continue;
            const float d = dot(p - q, p - q);
            if (d < bestD) bestD = d, best = q;
        }
    });
    return best;
}

}  // namespace sdft
