#include "sdftrace/bake/jump_flood.h"

#include <tbb/parallel_for.h>

#include <chrono>

#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/exec/thread_arena.h"

namespace sdft {

std::vector<Vec3> jumpFlood(const GridShape& s, std::vector<Vec3> seed, JfaVariant variant,
                            int threads, JfaStats* stats) {
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    const float h = s.voxelSize;
    auto at = [&](int i, int j, int k) { return (static_cast<size_t>(k) * vy + j) * vx + i; };
    std::vector<int> offsets;
    if (variant == JfaVariant::OnePlusJfa) offsets.push_back(1);
    int maxDim = std::max({vx, vy, vz});
    int step = 1;
    while (step * 2 < maxDim) step *= 2;
    for (; step >= 1; step /= 2) offsets.push_back(step);
    if (variant == JfaVariant::JfaPlusTwo) offsets.insert(offsets.end(), {2, 1});

    // Ping-pong buffers, one parallel sweep per offset.
    std::vector<Vec3> next;
    assignHuge(next, seed.size(), Vec3(kNoSeed));
    ThreadArena arena(threads);
    for (int off : offsets) {
        auto start = std::chrono::steady_clock::now();
        arena.execute([&] {
            tbb::parallel_for(0, vz, [&](int k) {
                for (int j = 0; j < vy; ++j)
                    for (int i = 0; i < vx; ++i) {
                        Vec3 p = s.origin + Vec3(i, j, k) * h;
                        Vec3 best = seed[at(i, j, k)];
                        float bestD = best.x == kNoSeed ? kNoSeed : dot(p - best, p - best);
                        for (int dk = -off; dk <= off; dk += off) {
                            int kk = k + dk;
                            if (kk < 0 || kk >= vz) continue;
                            for (int dj = -off; dj <= off; dj += off) {
                                int jj = j + dj;
                                if (jj < 0 || jj >= vy) continue;
                                for (int di = -off; di <= off; di += off) {
                                    int ii = i + di;
                                    if (ii < 0 || ii >= vx) continue;
                                    Vec3 q = seed[at(ii, jj, kk)];
                                    if (q.x == kNoSeed) continue;
                                    float d = dot(p - q, p - q);
                                    if (d < bestD) bestD = d, best = q;
                                }
                            }
                        }
                        next[at(i, j, k)] = best;
                    }
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
