#include "sdftrace/bake/verify_bake.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "sdftrace/core/macros.h"
#include "sdftrace/exec/thread_arena.h"
#include "sdftrace/field/sample_grid.h"

namespace sdft {

namespace {
BakeError summarize(std::vector<double>& e) {
    BakeError r;
    r.count = e.size();
    if (e.empty()) return r;
    std::sort(e.begin(), e.end());
    r.mean = std::accumulate(e.begin(), e.end(), 0.0) / e.size();
    r.p99 = e[std::min(e.size() - 1, e.size() * 99 / 100)];
    r.max = e.back();
    return r;
}
}  // namespace

BakeVerification verifyBake(const Grid& grid, const std::vector<float>& exact, float bandVoxels) {
    const GridShape& s = grid.shape();
    SDFT_CHECK(exact.size() == s.vertexCount());
    GridView v = grid.view();
    const float h = s.voxelSize, band = bandVoxels * h;
    std::vector<double> all, near;
    BakeVerification r;
    for (int k = 0; k <= s.cells[2]; ++k)
        for (int j = 0; j <= s.cells[1]; ++j)
            for (int i = 0; i <= s.cells[0]; ++i) {
                size_t idx = (static_cast<size_t>(k) * (s.cells[1] + 1) + j) * (s.cells[0] + 1) + i;
                float baked = v.vertex(i, j, k), ex = exact[idx];
                // On the surface itself (within 1% of a voxel) the sign is moot.
                if (std::fabs(ex) > 0.01f * h) {
                    const bool wrong = (baked < 0) != (ex < 0);
                    r.wrongSigns += wrong;
                    r.wrongSignsFar += wrong && std::fabs(ex) > 0.5f * h;
                    ++r.vertices;
                }
                bool stored = true;
                if (v.kind == GridKind::Sparse) {
                    // The block of the cell below the vertex, as GridView::vertex reads it.
                    int B = v.blockSize;
                    int ci = std::min(i, s.cells[0] - 1) / B, cj = std::min(j, s.cells[1] - 1) / B,
                        ck = std::min(k, s.cells[2] - 1) / B;
                    stored = v.blockData[v.blockSlot(ci, cj, ck)] >= 0;
                }
                if (!stored) continue;
                // Sparse grids store samples clamped to the band (background + one voxel).
                float exMag = v.kind == GridKind::Sparse
                                  ? std::fmin(std::fabs(ex), grid.background() + h)
                                  : std::fabs(ex);
                double e = std::fabs(std::fabs(baked) - exMag) / h;
                all.push_back(e);
                // The band of either field: a baked surface where there is none counts too.
                if (std::fabs(ex) < band || std::fabs(baked) < band) near.push_back(e);
            }
    r.all = summarize(all);
    r.band = summarize(near);
    return r;
}

FieldVerification verifyAgainstField(const Grid& grid, const Tape& tape, float bandVoxels,
                                     int threads) {
    const GridShape& s = grid.shape();
    FieldVerification r;
    r.vertices = verifyBake(grid, sampleVertices(tape, s, threads), bandVoxels);
    const float h = s.voxelSize, band = bandVoxels * h, invL = 1.0f / tape.lipschitz();
    // Every cell up to ~4M, else every stride-th along each axis.
    const double cells = static_cast<double>(s.cells[0]) * s.cells[1] * s.cells[2];
    const int stride = std::max(1, static_cast<int>(std::ceil(std::cbrt(cells / 4.0e6))));
    const GridView v = grid.view();
    std::vector<std::vector<double>> errors(static_cast<size_t>(s.cells[2]));
    std::vector<size_t> wrong(errors.size(), 0), signedCount(errors.size(), 0);
    ThreadArena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(0, s.cells[2], [&](int k) {
            if (k % stride) return;
            for (int j = 0; j < s.cells[1]; j += stride)
                for (int i = 0; i < s.cells[0]; i += stride) {
                    const Vec3 p = s.origin + Vec3(i + 0.5f, j + 0.5f, k + 0.5f) * h;
                    const float exact = tape.eval(p) * invL, baked = v.interpolate(p);
                    if (std::fabs(exact) > 0.01f * h) {
                        wrong[k] += (baked < 0) != (exact < 0);
                        ++signedCount[k];
                    }
                    if (std::fabs(exact) < band) errors[k].push_back(std::fabs(baked - exact) / h);
                }
        });
    });
    std::vector<double> all;
    for (size_t k = 0; k < errors.size(); ++k) {
        all.insert(all.end(), errors[k].begin(), errors[k].end());
        r.wrongSignCentres += wrong[k];
        r.signedCentres += signedCount[k];
    }
    r.centres = summarize(all);
    return r;
}

}  // namespace sdft
