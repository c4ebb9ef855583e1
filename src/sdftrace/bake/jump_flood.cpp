#include "sdftrace/bake/jump_flood.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstdint>

#include "sdftrace/bake/jump_flood_step.h"
#include "sdftrace/core/macros.h"
#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/exec/simd.h"
#include "sdftrace/exec/thread_arena.h"

namespace sdft {

std::vector<int> jumpFloodOffsets(const GridShape& s, JfaVariant variant) {
    std::vector<int> offsets;
    if (variant == JfaVariant::OnePlusJfa) offsets.push_back(1);
    const int maxDim = std::max({s.vertices(0), s.vertices(1), s.vertices(2)});
    int step = 1;
    while (step * 2 < maxDim) step *= 2;
    for (; step >= 1; step /= 2) offsets.push_back(step);
    if (variant == JfaVariant::JfaPlusTwo) offsets.insert(offsets.end(), {2, 1});
    return offsets;
}

namespace {

// Scratch of one row: the best point's coordinates and squared distance per vertex.
struct RowScratch {
    std::vector<float> x, y, z, d;
    explicit RowScratch(int n) : x(n), y(n), z(n), d(n) {}
};

// a where the mask m is all ones, else b.
inline float blend(uint32_t m, float a, float b) {
    return std::bit_cast<float>((std::bit_cast<uint32_t>(a) & m) |
                                (std::bit_cast<uint32_t>(b) & ~m));
}

// jumpFloodVertex for a whole row of vertices (j, k) at once, the CPU's sweep: each neighbour row
// in jumpFloodVertex's order (z, y, x ascending) is offered to every vertex of the row, so that
// each vertex sees its candidates in the same order and keeps the same one (strictly nearer
// wins). The bounds are tested once per row, and the inner loop is branch-free over the row's
// scratch (a point-less neighbour, x = kNoSeed, is at an infinite squared distance and never
// wins), so that it vectorizes.
inline void jumpFloodRow(const GridShape& s, const Vec3* seed, int j, int k, int offset, Vec3* out,
                         RowScratch& r) {
    const int vx = s.vertices(0);
    const Vec3 row = vertexPosition(s, 0, j, k);
    const float h = s.voxelSize;
    const Vec3* own = seed + vertexIndex(s, 0, j, k);
    float *bx = r.x.data(), *by = r.y.data(), *bz = r.z.data(), *bd = r.d.data();
    for (int i = 0; i < vx; ++i) {
        const Vec3 p(row.x + static_cast<float>(i) * h, row.y, row.z);
        bx[i] = own[i].x, by[i] = own[i].y, bz[i] = own[i].z;
        bd[i] = own[i].x == kNoSeed ? kNoSeed : dot(p - own[i], p - own[i]);
    }
    forEachJumpRow(s, j, k, offset, [&](int jj, int kk) {
        const float* other = &seed[vertexIndex(s, 0, jj, kk)].x;
        for (int di = -offset; di <= offset; di += offset) {
            // The vertices whose neighbour i + di lies in the row.
            const int lo = std::max(0, -di), hi = std::min(vx, vx - di);
            const float* q = other + 3 * di;
#pragma omp simd
            for (int i = lo; i < hi; ++i) {
                const float qx = q[3 * i], qy = q[3 * i + 1], qz = q[3 * i + 2];
                const float dx = row.x + static_cast<float>(i) * h - qx, dy = row.y - qy,
                            dz = row.z - qz;
                const float d = dx * dx + dy * dy + dz * dz;
                // Selected by a bit mask: GCC's if-conversion leaves ?: as branches here.
                const uint32_t m = 0u - static_cast<uint32_t>(d < bd[i]);
                bd[i] = blend(m, d, bd[i]);
                bx[i] = blend(m, qx, bx[i]);
                by[i] = blend(m, qy, by[i]);
                bz[i] = blend(m, qz, bz[i]);
            }
        }
    });
    for (int i = 0; i < vx; ++i) out[i] = Vec3(bx[i], by[i], bz[i]);
}

// The row built for AVX2 and for the baseline (core/macros.h); exec/simd.h picks. AVX2 loads the
// interleaved points 8 at a time, SSE2 2 at a time; both round alike.
SDFT_TARGET_AVX2 void jumpFloodRowAvx2(const GridShape& s, const Vec3* seed, int j, int k,
                                       int offset, Vec3* out, RowScratch& r) {
    jumpFloodRow(s, seed, j, k, offset, out, r);
}
SDFT_TARGET_BASELINE void jumpFloodRowBaseline(const GridShape& s, const Vec3* seed, int j, int k,
                                               int offset, Vec3* out, RowScratch& r) {
    jumpFloodRow(s, seed, j, k, offset, out, r);
}

}  // namespace

std::vector<Vec3> jumpFlood(const GridShape& s, std::vector<Vec3> seed, JfaVariant variant,
                            int threads, JfaStats* stats) {
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    // Ping-pong buffers, one parallel sweep per offset.
    std::vector<Vec3> next;
    assignHuge(next, seed.size(), Vec3(kNoSeed));
    ThreadArena arena(threads);
    for (int off : jumpFloodOffsets(s, variant)) {
        auto start = std::chrono::steady_clock::now();
        arena.execute([&] {
            tbb::parallel_for(0, vz, [&](int k) {
                RowScratch scratch(vx);
                const auto row = useAvx2() ? jumpFloodRowAvx2 : jumpFloodRowBaseline;
                for (int j = 0; j < vy; ++j)
                    row(s, seed.data(), j, k, off, next.data() + vertexIndex(s, 0, j, k), scratch);
            });
        });
        seed.swap(next);
        if (stats) {
            stats->offsets.push_back(off);
            stats->passSeconds.push_back(
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        }
    }
    return seed;
}

}  // namespace sdft
