#include "sdftrace/bake/exact_bake.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <memory>

#include "exact_sampler.h"
#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/exec/progress.h"

namespace sdft {

using detail::arenaThreads;
using detail::report;
using detail::RowSampler;

std::vector<float> bakeExactSamples(const MeshBvh& bvh, const GridShape& s, SignMethod sign,
                                    int threads, ExactBakeStats* stats, bool progress) {
    RowSampler sampler(bvh.mesh(), &bvh, s, sign);
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    std::vector<float> out;
    assignHuge(out, s.vertexCount(), 0.0f);
    std::atomic<size_t> queries{0}, signs{0}, filmSums{0};
    Progress bar("sdftrace bake: exact distances", static_cast<uint64_t>(vy) * vz,
                 progress && stderrIsTerminal());
    tbb::task_arena arena(arenaThreads(threads));
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, vy * vz),
                          [&](const tbb::blocked_range<int>& rows) {
                              for (int row = rows.begin(); row != rows.end(); ++row) {
                                  sampler.row(0, row % vy, row / vy, vx,
                                              out.data() + static_cast<size_t>(row) * vx, queries,
                                              signs, filmSums);
                              }
                              bar.advance(rows.size());
                          });
    });
    report(stats, queries, signs, filmSums);
    return out;
}

}  // namespace sdft
