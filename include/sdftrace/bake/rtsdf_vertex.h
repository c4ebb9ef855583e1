// One vertex of RTSDF's ray-sampled fine SDF (Tan et al. 2022, §2.1, §2.3, §2.5.1) and one line of
// the single bake's Lipschitz relaxation, as header functions: the CPU bake (rtsdf_bake.cpp, rays
// through Embree) and the GPU bake (gpu/gpu_bake.cu, rays through the LBVH) run the same code per
// vertex and per line, only the ray caster differs.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "sdftrace/field/grid.h"
#include "sdftrace/math/ray.h"

namespace sdft {

// SplitMix64: a per-vertex stream, so the result does not depend on the thread schedule.
struct SplitMix {
    uint64_t state;
    SDFT_HOST_DEVICE uint64_t next() {
        uint64_t z = (state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    SDFT_HOST_DEVICE float uniform() {
        return static_cast<float>(next() >> 40) * (1.0f / 16777216.0f);
    }
};

// A uniform direction on the sphere (Archimedes: z uniform in [-1, 1]).
SDFT_HOST_DEVICE inline Vec3 sphereDirection(SplitMix& rng) {
    const float z = 1 - 2 * rng.uniform(), phi = 6.2831853f * rng.uniform();
    const float r = sqrtf(maxf(0.0f, 1 - z * z));
    return {r * cosf(phi), r * sinf(phi), z};
}

// The direction stream of vertex `index` in the `frame`-th accumulated frame (0 for a single
// bake): each accumulated frame casts new directions.
SDFT_HOST_DEVICE inline uint64_t rtsdfRayStream(uint32_t seed, size_t index, int frame) {
    return (static_cast<uint64_t>(seed) << 40) ^ static_cast<uint64_t>(index) ^
           (static_cast<uint64_t>(frame) * 0x9E3779B97F4A7C15ull);
}

// What the rays of one vertex found: the minimum hit distance (inf when none hit) and how many
// struck front and back faces (§2.1's sign vote, after Wright 2015).
struct RtsdfRays {
    float best = INFINITY;
    int front = 0, back = 0;
};

// `rays` uniformly random rays from p; `caster(ray, tnear)` returns the first hit (a t, +inf on a
// miss, and `front`). They start a little behind p (tnear = -tiny): a vertex on the surface hits it
// at 0.
template <class Caster>
SDFT_HOST_DEVICE inline RtsdfRays castRtsdfRays(const Caster& caster, Vec3 p, uint64_t stream,
                                                int rays, float tiny) {
    SplitMix rng{stream};
    RtsdfRays out;
    for (int r = 0; r < rays; ++r) {
        const auto hit = caster(Ray{p, sphereDirection(rng)}, -tiny);
        if (hit.t == INFINITY) continue;
        out.best = minf(out.best, std::fabs(hit.t));
        (hit.front ? out.front : out.back) += 1;
    }
    return out;
}

// A single bake's value at a vertex inside the mask: the rays' minimum signed by their vote, the
// coarse value c where no ray hit.
SDFT_HOST_DEVICE inline float rtsdfSingleValue(float c, const RtsdfRays& r) {
    if (r.best == INFINITY) return c;
    return r.back > r.front ? -r.best : r.best;
}

// RTSDF §2.5.1, eq. 1 at a vertex inside the mask: this frame's coarse value c and rays; the
// history magnitude `fine` (inf where none) updated, the signed fine value returned.
SDFT_HOST_DEVICE inline float rtsdfAccumulate(float& fine, float alpha, float c, const RtsdfRays& r,
                                              float voxel) {
    // The previous magnitude decays towards this frame's coarse value, and the rays' minimum
    // replaces it where it is nearer. Without a previous value (the first frame, or a vertex
    // that just entered the mask) f_{t-1} is taken as c_t: a single ray's distance (often across
    // the object) would otherwise decay away over many frames.
    const float prior = fine == INFINITY ? std::fabs(c) : fine;
    const float m = minf(alpha * prior + (1 - alpha) * std::fabs(c), r.best);
    fine = m;
    // The sign: the coarse SDF's (recomputed every frame, so it never lags a moving surface)
    // beyond one coarse voxel of the surface, where it is reliable; nearer, this frame's vote, or
    // the coarse sign where its rays all missed. No vote is carried between frames: a ray from
    // inside a closed surface always hits a back face, so a miss means outside, and votes kept
    // from before a move named the old side (on a box moved 2.5 voxels, 287 wrong signs at one
    // ray per vertex with votes decaying by half per frame, none without).
    const bool near = std::fabs(c) <= 2 * voxel;
    return near && r.front + r.back > 0 ? (r.back > r.front ? -m : m) : copysignf(m, c);
}

// One line of the Lipschitz relaxation: n samples from f[base] with `stride`, forward then
// backward, each lowered to its same-sign predecessor's magnitude plus h (the L1 lower envelope
// along the line; Danielsson's sweeps, Liktor 2008 §3.2). Signs are kept, a crossing is not
// relaxed across.
SDFT_HOST_DEVICE inline void relaxLine(float* f, size_t base, size_t stride, int n, float h) {
    auto relax = [&](size_t from, size_t to) {
        const float u = f[from], v = f[to];
        if ((u < 0) != (v < 0)) return;
        const float limit = std::fabs(u) + h;
        if (std::fabs(v) > limit) f[to] = v < 0 ? -limit : limit;
    };
    for (int i = 1; i < n; ++i) relax(base + (i - 1) * stride, base + i * stride);
    for (int i = n - 2; i >= 0; --i) relax(base + (i + 1) * stride, base + i * stride);
}

// The coarse grid of the fine `shape`: half the resolution over the same region.
SDFT_HOST_DEVICE inline GridShape rtsdfCoarseShape(const GridShape& s) {
    GridShape coarse;
    for (int a = 0; a < 3; ++a) coarse.cells[a] = (s.cells[a] + 1) / 2;
    coarse.origin = s.origin;
    coarse.voxelSize = 2 * s.voxelSize;
    return coarse;
}

}  // namespace sdft
