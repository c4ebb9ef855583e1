// A parallel loop over a grid's vertices on exactly `threads` threads (0: all): z slabs are the
// tasks, x runs fastest; f(i, j, k, index, position).
#pragma once

#include <tbb/parallel_for.h>

#include "sdftrace/exec/thread_arena.h"
#include "sdftrace/field/grid.h"

namespace sdft {

template <class F>
void forEachVertex(const GridShape& s, int threads, F&& f) {
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    ThreadArena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(0, vz, [&](int k) {
            for (int j = 0; j < vy; ++j)
                for (int i = 0; i < vx; ++i)
                    f(i, j, k, (static_cast<size_t>(k) * vy + j) * vx + i,
                      s.origin + Vec3(i, j, k) * s.voxelSize);
        });
    });
}

}  // namespace sdft
