#include "sdftrace/bake/exact_bake.h"

#include <tbb/parallel_for.h>

#include <atomic>
#include <memory>

#include "exact_sampler.h"
#include "sdftrace/bake/closest_point_transform.h"
#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/exec/progress.h"
#include "sdftrace/exec/thread_arena.h"

namespace sdft {

using detail::report;
using detail::RowSampler;

const char* closestPointsName(ClosestPoints c) {
    return c == ClosestPoints::Transform ? "transform" : "bvh";
}

bool parseClosestPoints(const std::string& name, ClosestPoints& out) {
    for (ClosestPoints c : {ClosestPoints::Transform, ClosestPoints::Bvh}) {
        if (name == closestPointsName(c)) {
            out = c;
            return true;
        }
    }
    return false;
}

std::vector<float> bakeExactSamples(const MeshBvh& bvh, const GridShape& s, SignMethod sign,
                                    int threads, ExactBakeStats* stats, bool progress,
                                    ClosestPoints closest) {
    ThreadArena arena(threads);  // first: the sampler's winding-number tree builds on its threads
    RowSampler sampler(bvh.mesh(), &bvh, s, sign);
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    std::vector<float> out;
    assignHuge(out, s.vertexCount(), 0.0f);
    std::atomic<size_t> queries{0}, signs{0}, filmSums{0};
    const bool transform = closest == ClosestPoints::Transform;
    ClosestPointTransformStats ts;
    std::vector<BakeStage> stages;
    StageClock phases(stages);
    if (transform) {
        Progress bar("sdftrace bake: closest point transform", static_cast<uint64_t>(vy) + vz,
                     progress && stderrIsTerminal());
        arena.execute([&] { closestPointTransform(bvh.mesh(), s, out.data(), &ts, &bar); });
        phases.mark("closest point transform");
    }
    Progress bar(transform ? "sdftrace bake: signs" : "sdftrace bake: exact distances",
                 static_cast<uint64_t>(vy) * vz, progress && stderrIsTerminal());
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, vy * vz),
                          [&](const tbb::blocked_range<int>& rows) {
                              for (int row = rows.begin(); row != rows.end(); ++row) {
                                  float* r = out.data() + static_cast<size_t>(row) * vx;
                                  sampler.row(0, row % vy, row / vy, vx, r, queries, signs,
                                              filmSums, transform ? r : nullptr);
                              }
                              bar.advance(rows.size());
                          });
    });
    phases.mark(transform ? "signs" : "distances and signs");
    report(stats, queries, signs, filmSums);
    if (stats) {
        stats->phases = std::move(stages);
        stats->transformRows = ts.rows;
        stats->transformEvaluations = ts.evaluations;
    }
    return out;
}

}  // namespace sdft
