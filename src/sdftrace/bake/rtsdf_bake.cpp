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

// Makes the samples 1-Lipschitz along the axes where fine ray distances meet the coarse field (and
// where few rays overestimated a distance): |f| = min over same-sign neighbours u of |f_u| + h
// steps, the L1 lower envelope computed by forward and backward passes along each axis in turn
// (the distance transform's separability; Danielsson's sweeps, Liktor 2008 §3.2, in L1). It only
// lowers magnitudes, and the true distance is already 1-Lipschitz, so it never moves a value past
// the truth from above; signs are kept and a surface crossing is not relaxed across.
void relaxToLipschitz(std::vector<float>& f, const GridShape& s, int threads) {
    const int n[3] = {s.vertices(0), s.vertices(1), s.vertices(2)};
    const size_t stride[3] = {1, static_cast<size_t>(n[0]), static_cast<size_t>(n[0]) * n[1]};
    const float h = s.voxelSize;
    ThreadArena arena(threads);
    for (int axis = 0; axis < 3; ++axis) {
        const int a = (axis + 1) % 3, b = (axis + 2) % 3;
        arena.execute([&] {
            tbb::parallel_for(0, n[b], [&](int jb) {
                for (int ja = 0; ja < n[a]; ++ja) {
                    const size_t base = ja * stride[a] + jb * stride[b];
                    auto relax = [&](size_t from, size_t to) {
                        const float u = f[from], v = f[to];
                        if ((u < 0) != (v < 0)) return;
                        const float limit = std::fabs(u) + h;
                        if (std::fabs(v) > limit) f[to] = v < 0 ? -limit : limit;
                    };
                    for (int i = 1; i < n[axis]; ++i)
                        relax(base + (i - 1) * stride[axis], base + i * stride[axis]);
                    for (int i = n[axis] - 2; i >= 0; --i)
                        relax(base + (i + 1) * stride[axis], base + i * stride[axis]);
                }
            });
        });
    }
}

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

// Eq. 1's previous frame: none on the first frame or after the grid changed shape.
void startFrame(RtsdfHistory& h, const GridShape& s) {
    const bool carried = h.frames > 0 && h.shape.cells[0] == s.cells[0] &&
                         h.shape.cells[1] == s.cells[1] && h.shape.cells[2] == s.cells[2] &&
                         h.shape.origin.x == s.origin.x && h.shape.origin.y == s.origin.y &&
                         h.shape.origin.z == s.origin.z && h.shape.voxelSize == s.voxelSize;
    if (carried) return;
    h.shape = s;
    h.fine.assign(s.vertexCount(), INFINITY);
    h.frames = 0;
}

// RTSDF §2.5.1, eq. 1 at vertex idx inside the mask: this frame's coarse value c, the rays'
// minimum distance `best` (inf if none hit) and their front / back hits; the history updated,
// the signed fine value returned.
float accumulate(RtsdfHistory& h, size_t idx, float c, float best, int front, int back,
                 float voxel) {
    // The previous magnitude decays towards this frame's coarse value, and the rays' minimum
    // replaces it where it is nearer. Without a previous value (the first frame, or a vertex
    // that just entered the mask) f_{t-1} is taken as c_t: a single ray's distance (often across
    // the object) would otherwise decay away over many frames.
    const float previous = h.fine[idx];
    const float prior = previous == INFINITY ? std::fabs(c) : previous;
    const float m = std::fmin(h.alpha * prior + (1 - h.alpha) * std::fabs(c), best);
    h.fine[idx] = m;
    // The sign: the coarse SDF's (recomputed every frame, so it never lags a moving surface)
    // beyond one coarse voxel of the surface, where it is reliable; nearer, this frame's vote, or
    // the coarse sign where its rays all missed. No vote is carried between frames: a ray from
    // inside a closed surface always hits a back face, so a miss means outside, and votes kept
    // from before a move named the old side (on a box moved 2.5 voxels, 287 wrong signs at one
    // ray per vertex with votes decaying by half per frame, none without).
    const bool near = std::fabs(c) <= 2 * voxel;
    return near && front + back > 0 ? (back > front ? -m : m) : std::copysign(m, c);
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
    RtsdfHistory* h = o.history;
    if (h) startFrame(*h, s);
    std::atomic<size_t> refined{0}, missed{0};
    // Each accumulated frame casts new directions.
    const uint64_t frameSalt = h ? static_cast<uint64_t>(h->frames) * 0x9E3779B97F4A7C15ull : 0;
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
                    if (std::fabs(c) > mask) {
                        // eq. 1, c_t > d: the coarse value, the history forgotten
                        if (h) h->fine[idx] = INFINITY;
                        continue;
                    }
                    ++localRefined;
                    SplitMix rng{(static_cast<uint64_t>(o.seed) << 40) ^ idx ^ frameSalt};
                    float best = INFINITY;
                    int front = 0, back = 0;
                    for (int r = 0; r < o.rays; ++r) {
                        // A little behind the origin: vertices on the surface hit it at 0.
                        MeshBvh::Hit hit = bvh.firstHit({p, sphereDirection(rng)}, -tiny);
                        if (hit.t == INFINITY) continue;
                        best = std::fmin(best, std::fabs(hit.t));
                        (hit.front ? front : back) += 1;
                    }
                    if (best == INFINITY) ++localMissed;
                    if (h) {
                        out[idx] = accumulate(*h, idx, c, best, front, back, s.voxelSize);
                        continue;
                    }
                    if (best == INFINITY) continue;
                    out[idx] = back > front ? -best : best;
                }
            refined += localRefined;
            missed += localMissed;
        });
    });
    // A single bake is relaxed; accumulated frames are not: eq. 1 averages the rays' noise over
    // frames, and relaxing would spread a moving surface's ghost into its neighbours (on the
    // bunny circling at 6 degrees per frame: ghost 0.71 -> 0.86 voxels at 128 cells, and 70 ms
    // more per frame at 256).
    if (!h) relaxToLipschitz(out, s, threads);
    if (h) ++h->frames;
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
