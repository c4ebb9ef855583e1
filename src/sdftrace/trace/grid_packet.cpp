// Packets of eight rays through the two-level DDA (Jamriška 2010, §4.1; grid_dda.h has the walker,
// the empty-space skipping and the cell test). Each lane runs traceRay's state machine on its own
// ray, and the packet steps all eight together in AVX2 registers: the setup, the block walker's
// advance and restarts, the cell walk's start and steps with their mask bits. What a lane does a
// few times a ray runs lane by lane: the block tables' lookups (gathers took longer on the CPUs
// measured) and a masked cell's intersection test (grid_dda::intersectCell). The float operations
// are traceRay's, in the same order (no FMA: core/macros.h), so every lane ends with
// traceGridRay's result and counters, bit for bit (grid_packet_test.cpp). A lane does not wait for
// the others: one that leaves its surface block visits the next block in the next round while the
// others walk their cells.
#include <immintrin.h>

#include <cstdint>

#include "sdftrace/core/macros.h"
#include "sdftrace/exec/simd.h"
#include "sdftrace/trace/grid_dda.h"
#include "sdftrace/trace/grid_tracer.h"

namespace sdft {

namespace {

#if SDFT_HAVE_AVX2_DISPATCH

constexpr int kLanes = 8;
using F8 = float __attribute__((vector_size(kLanes * sizeof(float)), aligned(32)));
using I8 = int32_t __attribute__((vector_size(kLanes * sizeof(int32_t)), aligned(32)));
using Lanes = unsigned;  // bit l: lane l

SDFT_TARGET_AVX2 inline Lanes bitsOf(I8 m) {
    return static_cast<Lanes>(_mm256_movemask_ps((__m256)m));
}
SDFT_TARGET_AVX2 inline I8 maskOf(Lanes bits) {
    const I8 lane = {1, 2, 4, 8, 16, 32, 64, 128};
    return (lane & static_cast<int32_t>(bits)) != 0;
}
SDFT_TARGET_AVX2 inline F8 minOf(F8 a, F8 b) { return a < b ? a : b; }  // minf, lane by lane
SDFT_TARGET_AVX2 inline I8 load(const int32_t v[kLanes]) {
    I8 out;
    __builtin_memcpy(&out, v, sizeof out);
    return out;
}

// Halves of an I8 (lanes 0-3, 4-7) widened to 64 bits.
SDFT_TARGET_AVX2 inline __m256i wide(I8 v, int half) {
    const __m256i x = (__m256i)v;
    return _mm256_cvtepi32_epi64(half ? _mm256_extracti128_si256(x, 1) : _mm256_castsi256_si128(x));
}

// Word `bit / 64` of the masks of surface blocks `data` (B^3 / 64 words each) into `words`, per
// half of the lanes, for the lanes in `lanes` (the others keep theirs).
template <int B>
SDFT_TARGET_AVX2 inline void maskWords(const uint64_t* masks, I8 data, I8 bit, Lanes lanes,
                                       __m256i words[2]) {
    constexpr int kWordShift = B == 8 ? 3 : 0;  // log2 of the 64-bit words per mask
    const I8 m = maskOf(lanes);
    const auto* base = reinterpret_cast<const long long*>(masks);
    for (int half = 0; half < 2; ++half) {
        const __m256i word = _mm256_add_epi64(_mm256_slli_epi64(wide(data, half), kWordShift),
                                              _mm256_srli_epi64(wide(bit, half), 6));
        words[half] = _mm256_mask_i64gather_epi64(words[half], base, word, wide(m, half), 8);
    }
}

// Lanes whose cell has its bit set in its mask word.
SDFT_TARGET_AVX2 inline Lanes setBits(const __m256i words[2], I8 bit) {
    const __m256i one = _mm256_set1_epi64x(1), low6 = _mm256_set1_epi64x(63);
    Lanes out = 0;
    for (int half = 0; half < 2; ++half) {
        const __m256i shift = _mm256_and_si256(wide(bit, half), low6);
        const __m256i set = _mm256_and_si256(_mm256_srlv_epi64(words[half], shift), one);
        out |= static_cast<Lanes>(
                   _mm256_movemask_pd(_mm256_castsi256_pd(_mm256_cmpeq_epi64(set, one))))
               << (4 * half);
    }
    return out;
}

// A Dda (grid_dda.h) per lane: the current cube's index, its next boundary per axis, and t.
struct Walker {
    I8 idx[3];
    F8 next[3];
    F8 t;
};

// Dda::init on the lanes in `m`: at t, in cubes of edge `size` with indices in [lo, hi].
SDFT_TARGET_AVX2 inline void start(Walker& w, I8 m, F8 t, float size, const I8 lo[3],
                                   const I8 hi[3], const I8 step[3], const I8 up[3],
                                   const F8 org[3], const F8 dir[3], const F8 inv[3]) {
    for (int a = 0; a < 3; ++a) {
        const F8 at = org[a] + dir[a] * t;
        const I8 i = __builtin_convertvector((F8)_mm256_floor_ps((__m256)(at / size)), I8);
        const I8 idx = i < lo[a] ? lo[a] : (hi[a] < i ? hi[a] : i);
        const F8 next = step[a] != 0
                            ? (__builtin_convertvector(idx + up[a], F8) * size - org[a]) * inv[a]
                            : F8{} + kInfinity;
        w.idx[a] = m ? idx : w.idx[a];
        w.next[a] = m ? next : w.next[a];
    }
    w.t = m ? t : w.t;
}

// One step of a Dda (Dda::advance) on the lanes in `m`: the axis of the nearest boundary, its
// parameter as the new t, the index moved, the next boundary computed from the index. Returns the
// lanes whose index left [lo, hi].
SDFT_TARGET_AVX2 inline I8 advance(Walker& w, I8 m, const I8 step[3], const I8 up[3],
                                   const F8 org[3], const F8 inv[3], float size, const I8 lo[3],
                                   const I8 hi[3]) {
    const I8 xy = w.next[0] < w.next[1];
    const I8 ax0 = m & xy & (w.next[0] < w.next[2]);
    const I8 ax1 = m & ~xy & (w.next[1] < w.next[2]);
    const I8 ax2 = m & ~ax0 & ~ax1;
    const I8 ax[3] = {ax0, ax1, ax2};
    I8 out = {0, 0, 0, 0, 0, 0, 0, 0};
    for (int a = 0; a < 3; ++a) {
        w.t = ax[a] ? w.next[a] : w.t;
        w.idx[a] += ax[a] & step[a];
        const F8 boundary =
            (__builtin_convertvector(w.idx[a] + up[a], F8) * size - org[a]) * inv[a];
        w.next[a] = ax[a] ? boundary : w.next[a];
        out |= ax[a] & ((w.idx[a] < lo[a]) | (w.idx[a] > hi[a]));
    }
    return out;
}

template <int B>
struct Packet {
    GridTraceResult res[kLanes];
    float sign[kLanes];             // +1 for rays starting outside the solid
    F8 org[3], dir[3], inv[3], t1;  // the ray in grid units, its end in the grid
    I8 step[3], up[3];              // the step's sign per axis; 1 where it is positive
    I8 blockLo[3], blockHi[3];
    Walker blocks;
    F8 blockExit;  // where the current block is left (or t1)
    Walker cells;  // the cell walk inside a surface block
    I8 cellLo[3], cellHi[3], bit, data;
    // The mask word of each lane's cell, lanes 0-3 and 4-7 (B = 4: the block's whole mask, read
    // when the walk starts; B = 8: read at every step).
    __m256i words[2];
    I8 visits, cellSteps;  // traversal steps: blocks visited, cells stepped
    Lanes blockLanes = 0, cellLanes = 0;

    grid_dda::GridRay ray(int l) const {
        return {Vec3(org[0][l], org[1][l], org[2][l]), Vec3(dir[0][l], dir[1][l], dir[2][l])};
    }
};

// traceRay's setup (grid_dda::setup: the ray in grid units clipped to the grid's box, its sign)
// and its block walker, for rays[0..n). Returns the lanes whose ray meets the grid.
template <int B>
SDFT_TARGET_AVX2 Lanes startLanes(const GridView& g, Packet<B>& p, const Ray* rays,
                                  const float* tMin, const float* tMax, int n, float startSign) {
    static_assert(sizeof(Ray) == 6 * sizeof(float), "rays are gathered as 6 floats");
    const I8 lane = {0, 1, 2, 3, 4, 5, 6, 7};
    const I8 valid = lane < n;
    const __m256i index = (__m256i)(valid ? lane : I8{});
    const auto* base = reinterpret_cast<const float*>(rays);
    const __m256i ray = _mm256_mullo_epi32(index, _mm256_set1_epi32(6));
    const F8 lo = (F8)_mm256_i32gather_ps(tMin, index, 4);
    const F8 hi = (F8)_mm256_i32gather_ps(tMax, index, 4);
    const float toGrid = 1.0f / g.shape.voxelSize;  // Vec3 / float multiplies by the inverse
    I8 alive = valid & (lo <= hi);
    F8 t0 = lo, t1 = hi;
    for (int a = 0; a < 3; ++a) {
        const F8 o = ((F8)_mm256_i32gather_ps(base + a, ray, 4) - g.shape.origin[a]) * toGrid;
        const F8 d = (F8)_mm256_i32gather_ps(base + 3 + a, ray, 4) * toGrid;
        const I8 zero = d == 0;
        p.org[a] = o;
        p.dir[a] = d;
        p.inv[a] = zero ? F8{} + kInfinity : 1.0f / d;
        p.step[a] = (d < 0) - (d > 0);
        p.up[a] = (d > 0) & 1;
        p.blockLo[a] = I8{};
        p.blockHi[a] = I8{} + (g.blocks[a] - 1);
        // intersectBounds on [0, cells]: a slab at a time, NaN limits ignored.
        const float cells = static_cast<float>(g.shape.cells[a]);
        alive &= ~(zero & ((o < 0.0f) | (o > cells)));
        const F8 ta = (0.0f - o) * p.inv[a], tb = (cells - o) * p.inv[a];
        const I8 swap = ta > tb;
        const F8 near = swap ? tb : ta, far = swap ? ta : tb;
        t0 = ~zero & (near == near) ? (t0 > near ? t0 : near) : t0;
        t1 = ~zero & (far == far) ? (t1 < far ? t1 : far) : t1;
    }
    alive &= ~(t0 > t1);
    p.t1 = t1;
    start(p.blocks, alive, t0, static_cast<float>(B), p.blockLo, p.blockHi, p.step, p.up, p.org,
          p.dir, p.inv);
    const Lanes lanes = bitsOf(alive);
    for (Lanes v = lanes; v; v &= v - 1) {
        const int l = __builtin_ctz(v);
        p.sign[l] = grid_dda::raySign(g, rays[l], t0[l], t0[l] > lo[l], startSign);
    }
    return lanes;
}

// The lanes in `walk` enter their current block, a surface block (traverseBlock, walkMaskedCells'
// start: Dda::init at the block's entry with cells of size 1).
template <int B>
SDFT_TARGET_AVX2 void startWalks(const GridView& g, Packet<B>& p, Lanes walk) {
    const I8 m = maskOf(walk);
    for (int a = 0; a < 3; ++a) {
        const I8 lo = p.blocks.idx[a] * B, cells = I8{} + g.shape.cells[a];
        p.cellLo[a] = m ? lo : p.cellLo[a];
        p.cellHi[a] = m ? (lo + B < cells ? lo + B : cells) - 1 : p.cellHi[a];
    }
    start(p.cells, m, p.blocks.t, 1.0f, p.cellLo, p.cellHi, p.step, p.up, p.org, p.dir, p.inv);
    const I8* c = p.cells.idx;
    const I8 bit = ((c[2] - p.cellLo[2]) * B + (c[1] - p.cellLo[1])) * B + (c[0] - p.cellLo[0]);
    p.bit = m ? bit : p.bit;
}

// skipCube (grid_dda.h) on the lanes in `lanes`: no block (tile, shift 3) within `r` of the
// current one holds a sign-changing cell, so the walk restarts where the ray leaves that cube.
// Adds the lanes whose cube ends in the current block to `advancing` and those restarted further
// on to `restarted`; the others left the grid.
template <int B>
SDFT_TARGET_AVX2 void skipCubes(Packet<B>& p, Lanes lanes, I8 r, I8 shift, Lanes& advancing,
                                Lanes& restarted) {
    const I8 m = maskOf(lanes);
    const F8 unit = static_cast<float>(B) * __builtin_convertvector((I8{} + 1) << shift, F8);
    F8 tCube = F8{} + kInfinity;
    I8 c[3];
    for (int a = 0; a < 3; ++a) {
        c[a] = p.blocks.idx[a] >> shift;
        const I8 face = p.step[a] > 0 ? c[a] + r + 1 : c[a] - r;
        const F8 t = (__builtin_convertvector(face, F8) * unit - p.org[a]) * p.inv[a];
        tCube = p.step[a] != 0 ? minOf(tCube, t) : tCube;
    }
    const I8 left = m & (tCube >= p.t1);
    advancing |= bitsOf(m & ~left & (tCube <= p.blockExit));
    I8 go = m & ~left & ~(tCube <= p.blockExit);
    if (!bitsOf(go)) return;
    const float size = static_cast<float>(B);
    start(p.blocks, go, tCube, size, p.blockLo, p.blockHi, p.step, p.up, p.org, p.dir, p.inv);
    // Rounding can leave the point in the cube: step out of it block by block.
    for (;;) {
        I8 in = go;
        for (int a = 0; a < 3; ++a) {
            const I8 d = (p.blocks.idx[a] >> shift) - c[a];
            in &= (d >= -r) & (d <= r);
        }
        if (!bitsOf(in)) break;
        go &= ~advance(p.blocks, in, p.step, p.up, p.org, p.inv, size, p.blockLo, p.blockHi);
    }
    restarted |= bitsOf(go & (p.blocks.t < p.t1));
}

// traverseBlocks' visit of every lane's current block: walk it, skip a cube of empty blocks, or
// move on. The tables are read lane by lane; the rest runs on all lanes at once. Returns the lanes
// to advance.
template <int B>
SDFT_TARGET_AVX2 Lanes visitBlocks(const GridView& g, Packet<B>& p) {
    const Lanes lanes = p.blockLanes;
    const I8 m = maskOf(lanes);
    p.visits -= m;
    p.blockExit =
        m ? minOf(minOf(minOf(p.blocks.next[0], p.blocks.next[1]), p.blocks.next[2]), p.t1)
          : p.blockExit;
    const I8* b = p.blocks.idx;
    const I8 tiles = ((b[2] >> kTileShift) * g.tiles[1] + (b[1] >> kTileShift)) * g.tiles[0] +
                     (b[0] >> kTileShift);
    constexpr int kMask = kTileBlocks - 1;
    const I8 local =
        ((b[2] & kMask) << (2 * kTileShift)) | ((b[1] & kMask) << kTileShift) | (b[0] & kMask);
    alignas(32) int32_t data[kLanes] = {}, radius[kLanes] = {}, shift[kLanes] = {};
    Lanes walk = 0, skip = 0;
    for (Lanes v = lanes; v; v &= v - 1) {
        const int l = __builtin_ctz(v);
        const size_t tile = static_cast<uint32_t>(tiles[l]);
        if (g.tileSkip && g.tileSkip[tile] > 0) {
            radius[l] = g.tileSkip[tile] - 1;
            shift[l] = kTileShift;
            skip |= 1u << l;
            continue;
        }
        const size_t slot = static_cast<size_t>(g.tilePage[tile]) * kPageEntries + local[l];
        if (g.mayHoldHit(slot)) {
            data[l] = g.blockData[slot];
            walk |= 1u << l;
        } else if (g.blockSkip && g.blockSkip[slot] > 1) {
            radius[l] = g.blockSkip[slot] - 1;
            shift[l] = 0;
            skip |= 1u << l;
        }
    }
    Lanes advancing = lanes & ~walk & ~skip;
    if (walk) {
        p.data = maskOf(walk) ? load(data) : p.data;
        startWalks(g, p, walk);
        if (B == 4) maskWords<B>(g.cellMasks, p.data, p.bit, walk, p.words);
        p.cellLanes |= walk;
    }
    Lanes stay = 0;
    if (skip) skipCubes(p, skip, load(radius), load(shift), advancing, stay);
    p.blockLanes = stay;
    return advancing;
}

// One step of every lane's cell walk (walkMaskedCells' loop body). Returns the lanes whose walk
// ended without a hit, to advance to the next block.
template <int B>
SDFT_TARGET_AVX2 Lanes stepCells(const GridView& g, Packet<B>& p, const GridTraceOptions& o) {
    I8 m = maskOf(p.cellLanes);
    p.cellSteps -= m;
    const F8 tOut =
        minOf(minOf(minOf(p.cells.next[0], p.cells.next[1]), p.cells.next[2]), p.blockExit);
    if (B == 8) maskWords<B>(g.cellMasks, p.data, p.bit, p.cellLanes, p.words);
    for (Lanes test = setBits(p.words, p.bit) & p.cellLanes; test; test &= test - 1) {
        const int l = __builtin_ctz(test);
        const int x = p.cells.idx[0][l], y = p.cells.idx[1][l], z = p.cells.idx[2][l];
        float c[8], tHit;
        blockCellCornersOf<B>(g.blockSamples, g.blockNeighbors, p.data[l], x - p.cellLo[0][l],
                              y - p.cellLo[1][l], z - p.cellLo[2][l], c);
        GridTraceResult& res = p.res[l];
        if (grid_dda::intersectCell(g, p.ray(l), x, y, z, c, p.cells.t[l], tOut[l], p.sign[l], o,
                                    res, tHit)) {
            res.hit = true;
            res.t = tHit;
            p.cellLanes &= ~(1u << l);
        }
    }
    m = maskOf(p.cellLanes);
    I8 ended = m & (tOut >= p.blockExit);
    const I8 live = m & ~ended;
    const I8 before[3] = {p.cells.idx[0], p.cells.idx[1], p.cells.idx[2]};
    ended |= advance(p.cells, live, p.step, p.up, p.org, p.inv, 1.0f, p.cellLo, p.cellHi);
    p.bit += (p.cells.idx[0] - before[0]) + (p.cells.idx[1] - before[1]) * B +
             (p.cells.idx[2] - before[2]) * (B * B);
    const Lanes out = bitsOf(ended);
    p.cellLanes &= ~out;
    return out;
}

// Moves the lanes in `lanes` to their next block (traverseBlocks' last line); those that reach
// t1 or leave the grid are done.
template <int B>
SDFT_TARGET_AVX2 void advanceBlocks(Packet<B>& p, Lanes lanes) {
    I8 m = maskOf(lanes);
    m &= ~(p.blockExit >= p.t1);
    const I8 out = advance(p.blocks, m, p.step, p.up, p.org, p.inv, static_cast<float>(B),
                           p.blockLo, p.blockHi);
    p.blockLanes |= bitsOf(m & ~out);
}

template <int B>
SDFT_TARGET_AVX2 void tracePacket(const GridView& g, const Ray* rays, const float* tMin,
                                  const float* tMax, int n, const GridTraceOptions& o,
                                  float startSign, GridTraceResult* out) {
    Packet<B> p{};
    p.blockLanes = startLanes(g, p, rays, tMin, tMax, n, startSign);
    while (p.blockLanes | p.cellLanes) {
        Lanes advancing = p.blockLanes ? visitBlocks(g, p) : 0;
        if (p.cellLanes) advancing |= stepCells(g, p, o);
        if (advancing) advanceBlocks(p, advancing);
    }
    for (int l = 0; l < n; ++l) {
        out[l] = p.res[l];
        out[l].traversalSteps += p.visits[l] + p.cellSteps[l];
    }
}

SDFT_TARGET_AVX2 void traceGridRaysAvx2(const GridView& g, const Ray* rays, const float* tMin,
                                        const float* tMax, int n, const GridTraceOptions& o,
                                        float startSign, GridTraceResult* out) {
    for (int i = 0; i < n; i += kLanes) {
        const int k = n - i < kLanes ? n - i : kLanes;
        bool any = false;  // a packet the min/max buffer empties whole has nothing to trace
        for (int l = 0; l < k; ++l) any |= tMin[i + l] <= tMax[i + l];
        if (!any) {
            for (int l = 0; l < k; ++l) out[i + l] = GridTraceResult{};
            continue;
        }
        if (g.blockSize == 8)
            tracePacket<8>(g, rays + i, tMin + i, tMax + i, k, o, startSign, out + i);
        else
            tracePacket<4>(g, rays + i, tMin + i, tMax + i, k, o, startSign, out + i);
    }
}

#endif  // SDFT_HAVE_AVX2_DISPATCH

}  // namespace

void traceGridRays(const GridView& g, const Ray* rays, const float* tMin, const float* tMax, int n,
                   const GridTraceOptions& o, GridTraceResult* out, float startSign) {
#if SDFT_HAVE_AVX2_DISPATCH
    // Tile indices in 32 bits (a grid of 2^31 tiles would be 41,000 blocks across).
    const size_t tiles = static_cast<size_t>(g.tiles[0]) * g.tiles[1] * g.tiles[2];
    if (o.packets && tiles < (size_t{1} << 31) && useAvx2() && g.kind == GridKind::Sparse &&
        o.bitMasks && (g.blockSize == 4 || g.blockSize == 8)) {
        traceGridRaysAvx2(g, rays, tMin, tMax, n, o, startSign, out);
        return;
    }
#endif
    for (int i = 0; i < n; ++i)
        out[i] = tMin[i] <= tMax[i] ? traceGridRay(g, rays[i], tMin[i], tMax[i], o, startSign)
                                    : GridTraceResult{};
}

}  // namespace sdft
