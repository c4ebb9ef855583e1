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

// What the rays of one vertex found: the minimum hit distance (inf when none hit), whether that
// nearest hit struck a back face, and how many hits struck front and back faces: all of them
// (§2.1's vote, after Wright 2015) and those within reach (rtsdfReach).
struct RtsdfRays {
    float best = INFINITY;
    bool nearestBack = false;
    int front = 0, back = 0;        // within reach
    int frontAll = 0, backAll = 0;  // every hit
};

// The coarse SDF's distance at p, whose trilinear value is c: |c|, or where larger the lower bound
// its cell's corners give (a corner at distance |c_i| from the surface puts p at least
// |c_i| - |p - v_i| from it, 1-Lipschitz). Across an open mesh's hole the winding-number sign
// flips with no triangle there: the corners on either side hold +a and -a, and c passes through 0
// in mid-air; |c| alone made a surface there (6.7 voxels off on the Stanford bunny's base at 128
// cells), the corners' bound does not.
SDFT_HOST_DEVICE inline float rtsdfCoarseDistance(const GridView& coarse, Vec3 p, float c) {
    const GridShape& g = coarse.shape;
    const Vec3 u = (p - g.origin) * (1.0f / g.voxelSize);
    int i0[3];
    const float uc[3] = {u.x, u.y, u.z};
    for (int a = 0; a < 3; ++a) {
        const int i = static_cast<int>(floorf(uc[a]));
        i0[a] = i < 0 ? 0 : (i > g.cells[a] - 1 ? g.cells[a] - 1 : i);
    }
    float bound = std::fabs(c);
    const int vx = g.cells[0] + 1, vy = g.cells[1] + 1;
    for (int corner = 0; corner < 8; ++corner) {
        const int i = i0[0] + (corner & 1), j = i0[1] + ((corner >> 1) & 1),
                  k = i0[2] + ((corner >> 2) & 1);
        const float ci = coarse.samples[(static_cast<size_t>(k) * vy + j) * vx + i];
        const Vec3 v =
            g.origin +
            Vec3(static_cast<float>(i), static_cast<float>(j), static_cast<float>(k)) * g.voxelSize;
        bound = maxf(bound, std::fabs(ci) - length(p - v));
    }
    return bound;
}

// How far a hit may lie from a vertex whose coarse distance is cd (rtsdfCoarseDistance) and still
// be a hit on the surface nearest to it: cd plus one coarse voxel (2 fine voxels).
SDFT_HOST_DEVICE inline float rtsdfReach(float cd, float voxel) { return cd + 2 * voxel; }

// `rays` uniformly random rays from p; `caster(ray, tnear)` returns the first hit (a t, +inf on a
// miss, and `front`). They start a little behind p (tnear = -tiny): a vertex on the surface hits it
// at 0. Hits within `reach` vote.
template <class Caster>
SDFT_HOST_DEVICE inline RtsdfRays castRtsdfRays(const Caster& caster, Vec3 p, uint64_t stream,
                                                int rays, float tiny, float reach) {
    SplitMix rng{stream};
    RtsdfRays out;
    for (int r = 0; r < rays; ++r) {
        const auto hit = caster(Ray{p, sphereDirection(rng)}, -tiny);
        if (hit.t == INFINITY) continue;
        const float t = std::fabs(hit.t);
        if (t < out.best) {
            out.best = t;
            out.nearestBack = !hit.front;
        }
        if (t <= reach) (hit.front ? out.front : out.back) += 1;
        (hit.front ? out.frontAll : out.backAll) += 1;
    }
    return out;
}

// The side a vote names (a tie: the nearest hit's).
SDFT_HOST_DEVICE inline bool rtsdfVoteInside(int front, int back, const RtsdfRays& r) {
    return back != front ? back > front : r.nearestBack;
}

// The sign of a vertex with coarse value c (coarse distance cd, rtsdfCoarseDistance) and these
// rays, true for inside; `closed`: the mesh is watertight (isWatertight, triangle_mesh.h). §2.1
// signs by the majority of all hits' facings. On a closed mesh each ray's first hit tells the side
// (from outside a front face, from inside a back face), however far it lies; on an open mesh rays
// through its holes strike back faces from outside, and a ray that strays far from the vertex says
// little about it: with few rays that vote put 1-1.4% wrong signs and errors of 30-90 voxels in the
// band of the Stanford bunny and the elephant with holes (sdftrace bake --method rtsdf --verify;
// README). Here:
// - beyond one coarse voxel (2 fine voxels) of the surface, the coarse SDF's sign: its winding
//   numbers are reliable there;
// - nearer, the vote of the hits within reach, on the surface nearest to the vertex, where all
//   hits agree with it (or tie); where they disagree, the coarse sign: a near vote alone is misled
//   inside one part of a mesh next to another that pierces it (the teapot's spout through its
//   body), where the nearest sheet faces away but most rays see the enclosing surface's back
//   faces;
// - with no hit within reach, all hits' vote on a closed mesh, else the coarse sign.
SDFT_HOST_DEVICE inline bool rtsdfNegative(float c, float cd, const RtsdfRays& r, float voxel,
                                           bool closed) {
    const bool near = cd <= 2 * voxel;
    if (!near) return c < 0;
    const bool all = rtsdfVoteInside(r.frontAll, r.backAll, r);
    if (r.front + r.back == 0) return closed && r.frontAll + r.backAll > 0 ? all : c < 0;
    const bool local = rtsdfVoteInside(r.front, r.back, r);
    if (r.backAll != r.frontAll && all != local) return c < 0;
    return local;
}

// A single bake's value at a vertex inside the mask: the rays' minimum where a hit lies within
// reach, else the coarse distance cd (no ray found the surface the coarse field says is near: cd
// then lies nearer the true distance than the rays' minimum), signed by rtsdfNegative.
SDFT_HOST_DEVICE inline float rtsdfSingleValue(float c, float cd, const RtsdfRays& r, float voxel,
                                               bool closed) {
    const float m = r.front + r.back > 0 ? r.best : cd;
    return rtsdfNegative(c, cd, r, voxel, closed) ? -m : m;
}

// RTSDF §2.5.1, eq. 1 at a vertex inside the mask: this frame's coarse value c (its distance cd,
// rtsdfCoarseDistance) and rays; the history magnitude `fine` (inf where none) updated, the signed
// fine value returned.
SDFT_HOST_DEVICE inline float rtsdfAccumulate(float& fine, float alpha, float c, float cd,
                                              const RtsdfRays& r, float voxel, bool closed) {
    // The previous magnitude decays towards this frame's coarse value, and the rays' minimum
    // replaces it where it is nearer. Without a previous value (the first frame, or a vertex
    // that just entered the mask) f_{t-1} is taken as c_t: a single ray's distance (often across
    // the object) would otherwise decay away over many frames.
    const float prior = fine == INFINITY ? cd : fine;
    const float m = minf(alpha * prior + (1 - alpha) * cd, r.best);
    fine = m;
    // The sign (rtsdfNegative): the coarse SDF is recomputed every frame, so it never lags a
    // moving surface, and no vote is carried between frames: votes kept from before a move named
    // the old side (on a box moved 2.5 voxels, 287 wrong signs at one ray per vertex with votes
    // decaying by half per frame, none without).
    return rtsdfNegative(c, cd, r, voxel, closed) ? -m : m;
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
