#include "sdftrace/bake/jump_flood.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <array>
#include <chrono>
#include <cmath>

#include "sdftrace/bake/closest_point.h"
#include "sdftrace/bake/winding_number.h"

namespace sdft {

std::vector<Vec3> seedClosestPoints(const TriangleMesh& mesh, const GridShape& s) {
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    const size_t n = s.vertexCount();
    const float h = s.voxelSize;
    auto at = [&](int i, int j, int k) { return (static_cast<size_t>(k) * vy + j) * vx + i; };
    auto position = [&](int i, int j, int k) { return s.origin + Vec3(i, j, k) * h; };
    // Seeds: every vertex within half a cell diagonal of a triangle holds its closest point on the
    // nearest such triangle (sequential over triangles; each touches only its bounding box).
    std::vector<Vec3> seed(n, Vec3(kNoSeed));
    std::vector<float> seedDist(n, kNoSeed);
    const float reach = 0.87f * h;
    for (const auto& t : mesh.triangles) {
        Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
        Vec3 lo = (min(a, min(b, c)) - s.origin) / h - Vec3(1.0f),
             hi = (max(a, max(b, c)) - s.origin) / h + Vec3(1.0f);
        for (int k = std::max(0, int(std::floor(lo.z)));
             k <= std::min(vz - 1, int(std::ceil(hi.z))); ++k)
            for (int j = std::max(0, int(std::floor(lo.y)));
                 j <= std::min(vy - 1, int(std::ceil(hi.y))); ++j)
                for (int i = std::max(0, int(std::floor(lo.x)));
                     i <= std::min(vx - 1, int(std::ceil(hi.x))); ++i) {
                    Vec3 p = position(i, j, k);
                    Vec3 q = closestPointOnTriangle(p, a, b, c);
                    float d = length(p - q);
                    size_t idx = at(i, j, k);
                    if (d <= reach && d < seedDist[idx]) {
                        seedDist[idx] = d;
                        seed[idx] = q;
                    }
                }
    }

    return seed;
}

std::vector<float> signedFromSeeds(const TriangleMesh& mesh, const GridShape& s,
                                   const std::vector<Vec3>& seed, int threads) {
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    const size_t n = s.vertexCount();
    auto at = [&](int i, int j, int k) { return (static_cast<size_t>(k) * vy + j) * vx + i; };
    auto position = [&](int i, int j, int k) { return s.origin + Vec3(i, j, k) * s.voxelSize; };
    tbb::task_arena arena(threads > 0 ? threads : tbb::this_task_arena::max_concurrency());
    // Distances to the adopted seed points, signed by the winding number.
    WindingNumber winding(mesh);
    std::vector<float> out(n);
    arena.execute([&] {
        tbb::parallel_for(0, vz, [&](int k) {
            for (int j = 0; j < vy; ++j)
                for (int i = 0; i < vx; ++i) {
                    Vec3 p = position(i, j, k);
                    Vec3 q = seed[at(i, j, k)];
                    float d = q.x == kNoSeed ? kNoSeed : length(p - q);
                    out[at(i, j, k)] = winding.inside(p) ? -d : d;
                }
        });
    });
    return out;
}

std::vector<float> bakeDanielssonSamples(const TriangleMesh& mesh, const GridShape& s,
                                         int threads) {
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    auto at = [&](int i, int j, int k) { return (static_cast<size_t>(k) * vy + j) * vx + i; };
    std::vector<Vec3> seed = seedClosestPoints(mesh, s);
    // The 13 neighbours that precede a vertex in x-fastest raster order; the backward sweep uses
    // their negations.
    std::vector<std::array<int, 3>> before;
    for (int dk = -1; dk <= 0; ++dk)
        for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di)
                if (dk < 0 || (dk == 0 && (dj < 0 || (dj == 0 && di < 0))))
                    before.push_back({di, dj, dk});
    auto relax = [&](int i, int j, int k, int sign) {
        Vec3 p = s.origin + Vec3(i, j, k) * s.voxelSize;
        Vec3& best = seed[at(i, j, k)];
        float bestD = best.x == kNoSeed ? kNoSeed : dot(p - best, p - best);
        for (const auto& o : before) {
            int ii = i + sign * o[0], jj = j + sign * o[1], kk = k + sign * o[2];
            if (ii < 0 || jj < 0 || kk < 0 || ii >= vx || jj >= vy || kk >= vz) continue;
            Vec3 q = seed[at(ii, jj, kk)];
            if (q.x == kNoSeed) continue;
            float d = dot(p - q, p - q);
            if (d < bestD) bestD = d, best = q;
        }
    };
    for (int k = 0; k < vz; ++k)
        for (int j = 0; j < vy; ++j)
            for (int i = 0; i < vx; ++i) relax(i, j, k, 1);
    for (int k = vz - 1; k >= 0; --k)
        for (int j = vy - 1; j >= 0; --j)
            for (int i = vx - 1; i >= 0; --i) relax(i, j, k, -1);
    return signedFromSeeds(mesh, s, seed, threads);
}

std::vector<float> bakeJumpFloodSamples(const TriangleMesh& mesh, const GridShape& s,
                                        JfaVariant variant, int threads, JfaStats* stats) {
    auto start = std::chrono::steady_clock::now();
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    const size_t n = s.vertexCount();
    const float h = s.voxelSize;
    auto at = [&](int i, int j, int k) { return (static_cast<size_t>(k) * vy + j) * vx + i; };
    auto position = [&](int i, int j, int k) { return s.origin + Vec3(i, j, k) * h; };

    std::vector<Vec3> seed = seedClosestPoints(mesh, s);

    // Jump flooding with ping-pong buffers, one parallel sweep per offset.
    std::vector<Vec3> next(n);
    std::vector<int> offsets;
    if (variant == JfaVariant::OnePlusJfa) offsets.push_back(1);
    int maxDim = std::max({vx, vy, vz});
    int step = 1;
    while (step * 2 < maxDim) step *= 2;
    for (; step >= 1; step /= 2) offsets.push_back(step);
    if (variant == JfaVariant::JfaPlusTwo) offsets.insert(offsets.end(), {2, 1});
    tbb::task_arena arena(threads > 0 ? threads : tbb::this_task_arena::max_concurrency());
    for (int off : offsets) {
        arena.execute([&] {
            tbb::parallel_for(0, vz, [&](int k) {
                for (int j = 0; j < vy; ++j)
                    for (int i = 0; i < vx; ++i) {
                        Vec3 p = position(i, j, k);
                        Vec3 best = seed[at(i, j, k)];
                        float bestD = best.x == kNoSeed ? kNoSeed : dot(p - best, p - best);
                        for (int dk = -off; dk <= off; dk += off)
                            for (int dj = -off; dj <= off; dj += off)
                                for (int di = -off; di <= off; di += off) {
                                    int ii = i + di, jj = j + dj, kk = k + dk;
                                    if (ii < 0 || jj < 0 || kk < 0 || ii >= vx || jj >= vy ||
                                        kk >= vz)
                                        continue;
                                    Vec3 q = seed[at(ii, jj, kk)];
                                    if (q.x == kNoSeed) continue;
                                    float d = dot(p - q, p - q);
                                    if (d < bestD) bestD = d, best = q;
                                }
                        next[at(i, j, k)] = best;
                    }
            });
        });
        seed.swap(next);
    }

    std::vector<float> out = signedFromSeeds(mesh, s, seed, threads);
    if (stats) {
        stats->passes = static_cast<int>(offsets.size());
        stats->seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return out;
}

}  // namespace sdft
