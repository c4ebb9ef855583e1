#include "sdftrace/bake/separable_edt.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>

#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/exec/thread_arena.h"
#include "sdftrace/field/lower_envelope.h"

namespace sdft {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

std::vector<Vec3> separableEdt(const GridShape& s, const std::vector<Vec3>& seeds, int threads) {
    const int n[3] = {s.vertices(0), s.vertices(1), s.vertices(2)};
    const size_t stride[3] = {1, static_cast<size_t>(n[0]), static_cast<size_t>(n[0]) * n[1]};
    const size_t count = s.vertexCount();
    std::vector<double> dist;
    assignHuge(dist, count, 0.0);
    std::vector<int32_t> feature;
    assignHuge(feature, count, int32_t{-1});  // linear index of the nearest seed vertex, -1 if none
    for (size_t i = 0; i < count; ++i) {
        bool seed = seeds[i].x != kNoSeed;
        int vi = static_cast<int>(i % n[0]), vj = static_cast<int>((i / n[0]) % n[1]),
            vk = static_cast<int>(i / stride[2]);
        Vec3 off = (seeds[i] - (s.origin + Vec3(vi, vj, vk) * s.voxelSize)) / s.voxelSize;
        dist[i] = seed ? double(dot(off, off)) : kInf;
        feature[i] = seed ? static_cast<int32_t>(i) : -1;
    }
    ThreadArena arena(threads);
    for (int axis = 0; axis < 3; ++axis) {
        const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3, len = n[axis];
        arena.execute([&] {
            tbb::parallel_for(0, n[a2], [&](int c2) {
                std::vector<double> f(len), out(len), z(len + 1);
                std::vector<int> from(len), v(len);
                std::vector<int32_t> feat(len);
                for (int c1 = 0; c1 < n[a1]; ++c1) {
                    size_t base = c1 * stride[a1] + c2 * stride[a2];
                    for (int q = 0; q < len; ++q) {
                        f[q] = dist[base + q * stride[axis]];
                        feat[q] = feature[base + q * stride[axis]];
                    }
                    lowerEnvelope(len, f.data(), out.data(), from.data(), v.data(), z.data());
                    for (int q = 0; q < len; ++q) {
                        dist[base + q * stride[axis]] = out[q];
                        feature[base + q * stride[axis]] = from[q] < 0 ? -1 : feat[from[q]];
                    }
                }
            });
        });
    }
    std::vector<Vec3> points;
    assignHuge(points, count, Vec3(kNoSeed));
    for (size_t i = 0; i < count; ++i)
        if (feature[i] >= 0) points[i] = seeds[feature[i]];
    // The nearest seed *vertex* need not hold the nearest surface point (seeds sit up to 0.87 h
    // from the surface); one pass over the 26 neighbours' points repairs most of that.
    std::vector<Vec3> out;
    assignHuge(out, count, Vec3(kNoSeed));
    arena.execute([&] {
        tbb::parallel_for(0, n[2], [&](int k) {
            for (int j = 0; j < n[1]; ++j)
                for (int i = 0; i < n[0]; ++i) {
                    Vec3 p = s.origin + Vec3(i, j, k) * s.voxelSize;
                    size_t idx = i + j * stride[1] + k * stride[2];
                    Vec3 best = points[idx];
                    float bestD = best.x == kNoSeed ? kNoSeed : dot(p - best, p - best);
                    for (int dk = -1; dk <= 1; ++dk)
                        for (int dj = -1; dj <= 1; ++dj)
                            for (int di = -1; di <= 1; ++di) {
                                int ii = i + di, jj = j + dj, kk = k + dk;
                                if (ii < 0 || jj < 0 || kk < 0 || ii >= n[0] || jj >= n[1] ||
                                    kk >= n[2])
                                    continue;
                                Vec3 q = points[ii + jj * stride[1] + kk * stride[2]];
                                if (q.x == kNoSeed) continue;
                                float d = dot(p - q, p - q);
                                if (d < bestD) bestD = d, best = q;
                            }
                    out[idx] = best;
                }
        });
    });
    return out;
}

}  // namespace sdft
