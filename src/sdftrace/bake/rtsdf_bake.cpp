#include "sdftrace/bake/rtsdf_bake.h"

#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>

#include "sdftrace/bake/jump_flood.h"
#include "sdftrace/bake/lbvh.h"
#include "sdftrace/bake/rtsdf_vertex.h"
#include "sdftrace/bake/seed_signs.h"
#include "sdftrace/core/macros.h"
#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/exec/thread_arena.h"

namespace sdft {

namespace {

// Makes the samples 1-Lipschitz along the axes where fine ray distances meet the coarse field (and
// where few rays overestimated a distance): relaxLine (rtsdf_vertex.h) over every line of each
// axis in turn (the distance transform's separability). It only lowers magnitudes, and the true
// distance is already 1-Lipschitz, so it never moves a value past the truth from above.
void relaxToLipschitz(std::vector<float>& f, const GridShape& s, int threads) {
    const int n[3] = {s.vertices(0), s.vertices(1), s.vertices(2)};
    const size_t stride[3] = {1, static_cast<size_t>(n[0]), static_cast<size_t>(n[0]) * n[1]};
    ThreadArena arena(threads);
    for (int axis = 0; axis < 3; ++axis) {
        const int a = (axis + 1) % 3, b = (axis + 2) % 3;
        arena.execute([&] {
            tbb::parallel_for(0, n[b], [&](int jb) {
                for (int ja = 0; ja < n[a]; ++ja)
                    relaxLine(f.data(), ja * stride[a] + jb * stride[b], stride[axis], n[axis],
                              s.voxelSize);
            });
        });
    }
}

double since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

inline void interpolateRow(const GridView& cv, const GridShape& s, int j, int k, float* out) {
    const Vec3 row = vertexPosition(s, 0, j, k);
    const GridShape& c = cv.shape;
    // GridView::locate's arithmetic: (p - origin) * (1 / voxel), clamped to the grid.
    const float inv = 1.0f / c.voxelSize;
    const float fy = clampf((row.y - c.origin.y) * inv, 0.0f, static_cast<float>(c.cells[1]));
    const float fz = clampf((row.z - c.origin.z) * inv, 0.0f, static_cast<float>(c.cells[2]));
    const int cj = clampi(static_cast<int>(fy), 0, c.cells[1] - 1);
    const int ck = clampi(static_cast<int>(fz), 0, c.cells[2] - 1);
    const float v = fy - cj, w = fz - ck;
    const size_t sy = static_cast<size_t>(c.cells[0]) + 1, sz = sy * (c.cells[1] + 1);
    const float* r00 = cv.samples + static_cast<size_t>(ck) * sz + static_cast<size_t>(cj) * sy;
    const float *r10 = r00 + sy, *r01 = r00 + sz, *r11 = r00 + sz + sy;
    const float nx = static_cast<float>(c.cells[0]);
    const int n = s.vertices(0);
    for (int i = 0; i < n; ++i) {
        const float fx =
            clampf((row.x + static_cast<float>(i) * s.voxelSize - c.origin.x) * inv, 0.0f, nx);
        const int ci = clampi(static_cast<int>(fx), 0, c.cells[0] - 1);
        const float corners[8] = {r00[ci], r00[ci + 1], r10[ci], r10[ci + 1],
                                  r01[ci], r01[ci + 1], r11[ci], r11[ci + 1]};
        out[i] = trilinear(corners, fx - ci, v, w);
    }
}

// The coarse SDF (§2.2): jump flooding at half the resolution over the same region, signed.
std::vector<float> coarseField(const TriangleMesh& mesh, const MeshBvh& bvh,
                               const GridShape& coarse, SignMethod sign, int threads) {
    SurfaceSeeds seeds = seedSurfaceVertices(mesh, coarse, threads);
    std::vector<float> samples = distancesToPoints(
        coarse, jumpFlood(coarse, seeds.point, JfaVariant::Plain, threads), threads);
    signDistances(samples, mesh, &bvh, coarse, seeds, sign, 0.5f, threads);
    return samples;
}

}  // namespace

void interpolateDenseRow(const GridView& coarse, const GridShape& fine, int j, int k, float* out) {
    SDFT_CHECK(coarse.kind == GridKind::Dense);
    interpolateRow(coarse, fine, j, k, out);
}

bool rtsdfMeshClosed(RtsdfHistory* history, const TriangleMesh& mesh) {
    if (!history) return isWatertight(mesh);
    // FNV-1a over the indices, and their count: 0 stands for none.
    uint64_t hash = 14695981039346656037ull ^ mesh.triangles.size();
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t) hash = (hash ^ v) * 1099511628211ull;
    hash |= 1;
    if (hash != history->topology) {
        history->topology = hash;
        history->closed = isWatertight(mesh);
    }
    return history->closed;
}

void beginRtsdfFrame(RtsdfHistory& h, const GridShape& s) {
    const bool carried = h.frames > 0 && h.fine.size() == s.vertexCount() &&
                         h.shape.cells[0] == s.cells[0] && h.shape.cells[1] == s.cells[1] &&
                         h.shape.cells[2] == s.cells[2] && h.shape.origin.x == s.origin.x &&
                         h.shape.origin.y == s.origin.y && h.shape.origin.z == s.origin.z &&
                         h.shape.voxelSize == s.voxelSize;
    if (carried) return;
    h.shape = s;
    h.fine.assign(s.vertexCount(), INFINITY);
    h.frames = 0;
}

std::vector<float> bakeRtsdfSamples(const TriangleMesh& mesh, const MeshBvh& bvh,
                                    const GridShape& s, const RtsdfOptions& o, int threads,
                                    RtsdfStats* stats) {
    auto start = std::chrono::steady_clock::now();
    const GridShape coarse = rtsdfCoarseShape(s);
    const std::vector<float> coarseSamples = coarseField(mesh, bvh, coarse, o.coarseSign, threads);
    // Read by trilinear interpolation only: a view, no Grid (whose Lipschitz scan of every cell
    // nothing here reads).
    GridView cv;
    cv.kind = GridKind::Dense;
    cv.shape = coarse;
    cv.samples = coarseSamples.data();
    double coarseSeconds = since(start);

    // The fine SDF: rays from the vertices inside the mask.
    start = std::chrono::steady_clock::now();
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    const float mask = o.maskVoxels * s.voxelSize, tiny = 1e-4f * s.voxelSize;
    std::vector<float> out;
    assignHuge(out, s.vertexCount(), 0.0f);
    RtsdfHistory* h = o.history;
    if (h) beginRtsdfFrame(*h, s);
    const bool closed = rtsdfMeshClosed(h, mesh);
    std::atomic<size_t> refined{0}, missed{0};
    const int frame = h ? h->frames : 0;
    // The rays through Embree, or through the LBVH the GPU bake traverses (the same header code).
    std::unique_ptr<Lbvh> lbvh;
    if (o.caster == RtsdfCaster::Lbvh) lbvh = std::make_unique<Lbvh>(mesh, threads);
    const LbvhCaster lbvhCaster{lbvh ? lbvh->view() : LbvhView{}};
    auto embreeCaster = [&bvh](const Ray& ray, float tnear) { return bvh.firstHit(ray, tnear); };
    auto castRays = [&](Vec3 p, size_t idx, float cd) {
        const uint64_t stream = rtsdfRayStream(o.seed, idx, frame);
        const float reach = rtsdfReach(cd, s.voxelSize);
        return lbvh ? castRtsdfRays(lbvhCaster, p, stream, o.rays, tiny, reach)
                    : castRtsdfRays(embreeCaster, p, stream, o.rays, tiny, reach);
    };
    ThreadArena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(0, vz, [&](int k) {
            size_t localRefined = 0, localMissed = 0;
            for (int j = 0; j < vy; ++j) {
                float* row = out.data() + vertexIndex(s, 0, j, k);
                interpolateDenseRow(cv, s, j, k, row);  // the coarse value everywhere
                for (int i = 0; i < vx; ++i) {
                    const size_t idx = vertexIndex(s, i, j, k);
                    const Vec3 p = vertexPosition(s, i, j, k);
                    const float c = row[i];
                    if (std::fabs(c) > mask) {
                        // eq. 1, c_t > d: the coarse value, the history forgotten
                        if (h) h->fine[idx] = INFINITY;
                        continue;
                    }
                    ++localRefined;
                    const float cd = rtsdfCoarseDistance(cv, p, c);
                    const RtsdfRays rays = castRays(p, idx, cd);
                    localMissed += rays.best == INFINITY;
                    out[idx] = h ? rtsdfAccumulate(h->fine[idx], h->alpha, c, cd, rays, s.voxelSize,
                                                   closed)
                                 : rtsdfSingleValue(c, cd, rays, s.voxelSize, closed);
                }
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
