#include "sdftrace/bake/rtsdf_bake.h"

#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <cmath>

#include "sdftrace/bake/jump_flood.h"
#include "sdftrace/bake/seed_signs.h"
#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/exec/thread_arena.h"

namespace sdft {

namespace {

// SplitMix64: a per-vertex stream, so the result does not depend on the thread schedule.
struct SplitMix {
    uint64_t state;
    uint64_t next() {
        uint64_t z = (state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    float uniform() { return static_cast<float>(next() >> 40) * (1.0f / 16777216.0f); }
};

// A uniform direction on the sphere (Archimedes: z uniform in [-1, 1]).
Vec3 sphereDirection(SplitMix& rng) {
    float z = 1 - 2 * rng.uniform(), phi = 6.2831853f * rng.uniform();
    float r = std::sqrt(std::fmax(0.0f, 1 - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
}

double since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

std::vector<float> bakeRtsdfSamples(const TriangleMesh& mesh, const MeshBvh& bvh,
                                    const GridShape& s, const RtsdfOptions& o, int threads,
                                    RtsdfStats* stats) {
    auto start = std::chrono::steady_clock::now();
    // The coarse SDF: jump flooding at half the resolution over the same region.
    GridShape coarse;
    for (int a = 0; a < 3; ++a) coarse.cells[a] = (s.cells[a] + 1) / 2;
    coarse.origin = s.origin;
    coarse.voxelSize = 2 * s.voxelSize;
    SurfaceSeeds seeds = seedSurfaceVertices(mesh, coarse, threads);
    std::vector<float> coarseSamples = distancesToPoints(
        coarse, jumpFlood(coarse, seeds.point, JfaVariant::Plain, threads), threads);
    signDistances(coarseSamples, mesh, &bvh, coarse, seeds, o.coarseSign, 0.5f, threads);
    Grid coarseGrid = Grid::dense(coarse, std::move(coarseSamples));
    GridView cv = coarseGrid.view();
    double coarseSeconds = since(start);

    // The fine SDF: rays from the vertices inside the mask.
    start = std::chrono::steady_clock::now();
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    const float mask = o.maskVoxels * s.voxelSize, tiny = 1e-4f * s.voxelSize;
    std::vector<float> out;
    assignHuge(out, s.vertexCount(), 0.0f);
    std::atomic<size_t> refined{0}, missed{0};
    ThreadArena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(0, vz, [&](int k) {
            size_t localRefined = 0, localMissed = 0;
            for (int j = 0; j < vy; ++j)
                for (int i = 0; i < vx; ++i) {
                    size_t idx = (static_cast<size_t>(k) * vy + j) * vx + i;
                    Vec3 p = s.origin + Vec3(i, j, k) * s.voxelSize;
                    float c = cv.interpolate(p);
                    out[idx] = c;
                    if (std::fabs(c) > mask) continue;
                    ++localRefined;
                    SplitMix rng{(static_cast<uint64_t>(o.seed) << 40) ^ idx};
                    float best = INFINITY;
                    int front = 0, back = 0;
                    for (int r = 0; r < o.rays; ++r) {
                        // A little behind the origin: vertices on the surface hit it at 0.
                        MeshBvh::Hit hit = bvh.firstHit({p, sphereDirection(rng)}, -tiny);
                        if (hit.t == INFINITY) continue;
                        best = std::fmin(best, std::fabs(hit.t));
                        (hit.front ? front : back) += 1;
                    }
                    if (best == INFINITY) {
                        ++localMissed;
                        continue;
                    }
                    out[idx] = back > front ? -best : best;
                }
            refined += localRefined;
            missed += localMissed;
        });
    });
    if (stats) {
        stats->refined = refined.load();
        stats->rays = stats->refined * o.rays;
        stats->missed = missed.load();
        stats->coarseSeconds = coarseSeconds;
        stats->raySeconds = since(start);
    }
    return out;
}

}  // namespace sdft
