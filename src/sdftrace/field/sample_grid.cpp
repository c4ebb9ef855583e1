#include "sdftrace/field/sample_grid.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "sdftrace/core/macros.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/exec/progress.h"
#include "sdftrace/exec/thread_arena.h"

namespace sdft {

GridShape gridShapeFor(const Bounds3& region, const SampleOptions& o) {
    SDFT_CHECK(region.finite() && !region.empty() && o.resolution >= 1);
    float pad = o.paddingVoxels + (o.kind == GridKind::Sparse ? o.bandVoxels : 0);
    Vec3 extent = region.extent();
    float longest = std::max(maxComponent(extent), 1e-6f);
    // h such that the padded longest axis spans `resolution` cells.
    float h = longest / std::max(1.0f, o.resolution - 2 * pad);
    GridShape s;
    for (int a = 0; a < 3; ++a) {
        s.cells[a] = std::max(1, static_cast<int>(std::ceil(extent[a] / h + 2 * pad)));
    }
    s.voxelSize = h;
    Vec3 size = Vec3(s.cells[0], s.cells[1], s.cells[2]) * h;
    s.origin = region.center() - size * 0.5f;
    return s;
}

std::vector<float> sampleVertices(const Tape& tape, const GridShape& s, int threads,
                                  Progress* progress) {
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    std::vector<float> out(s.vertexCount());
    const float invL = 1.0f / tape.lipschitz();
    struct Scratch {
        std::vector<float> x, y, z;
        BatchScratch batch;
    };
    tbb::enumerable_thread_specific<Scratch> scratch;
    ThreadArena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(
            tbb::blocked_range<int>(0, vy * vz), [&](const tbb::blocked_range<int>& rows) {
                Scratch& sc = scratch.local();
                sc.x.resize(vx);
                sc.y.resize(vx);
                sc.z.resize(vx);
                for (int row = rows.begin(); row != rows.end(); ++row) {
                    int j = row % vy, k = row / vy;
                    for (int i = 0; i < vx; ++i) {
                        sc.x[i] = s.origin.x + i * s.voxelSize;
                        sc.y[i] = s.origin.y + j * s.voxelSize;
                        sc.z[i] = s.origin.z + k * s.voxelSize;
                    }
                    float* dst = out.data() + static_cast<size_t>(row) * vx;
                    tape.evalBatch(sc.x.data(), sc.y.data(), sc.z.data(), dst, vx, sc.batch);
                    for (int i = 0; i < vx; ++i) dst[i] *= invL;
                }
                if (progress) progress->advance(rows.size());
            });
    });
    return out;
}

Grid sampleGrid(const Tape& tape, const Bounds3& region, const SampleOptions& o) {
    GridShape shape = gridShapeFor(region, o);
    // Every vertex is sampled first (sparse grids keep only their surface blocks afterwards).
    checkMemoryBudget(static_cast<double>(shape.vertexCount()) * sizeof(float) *
                          (o.kind == GridKind::Dense ? 1 : 2),
                      "resolution " + std::to_string(o.resolution),
                      "the grid's samples at " + std::to_string(shape.cells[0]) + "x" +
                          std::to_string(shape.cells[1]) + "x" + std::to_string(shape.cells[2]) +
                          " cells",
                      "use a lower resolution");
    std::vector<float> samples;
    {
        Progress progress("sampling", static_cast<uint64_t>(shape.vertices(1)) * shape.vertices(2),
                          o.progress);
        samples = sampleVertices(tape, shape, o.threads, &progress);
    }
    if (o.kind == GridKind::Dense) return Grid::dense(shape, std::move(samples));
    return Grid::sparseFromDense(shape, samples, o.blockSize, o.bandVoxels);
}

}  // namespace sdft
