#include "sdftrace/bake/jump_flood.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>

#include "sdftrace/bake/jump_flood_step.h"
#include "sdftrace/exec/huge_pages.h"
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
                for (int j = 0; j < vy; ++j)
                    for (int i = 0; i < vx; ++i)
                        next[vertexIndex(s, i, j, k)] =
                            jumpFloodVertex(s, seed.data(), i, j, k, off);
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
