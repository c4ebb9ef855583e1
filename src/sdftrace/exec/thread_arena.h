// Work on exactly the requested number of threads: a TBB task arena of `threads` workers (0: all
// hardware threads), with TBB's global parallelism limited to it while it lives, so nested
// parallel loops stay within it too. Every renderer and bake stage runs its parallel loops in one.
#pragma once

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <utility>

namespace sdft {

// The thread count a `threads` setting means: itself, or all hardware threads for 0.
inline int resolveThreads(int threads) {
    return threads > 0 ? threads : tbb::this_task_arena::max_concurrency();
}

class ThreadArena {
  public:
    explicit ThreadArena(int threads)
        : m_threads(resolveThreads(threads)),
          m_limit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(m_threads)),
          m_arena(m_threads) {}

    int threads() const { return m_threads; }
    template <class F>
    decltype(auto) execute(F&& f) {
        return m_arena.execute(std::forward<F>(f));
    }

  private:
    int m_threads;
    tbb::global_control m_limit;
    tbb::task_arena m_arena;
};

}  // namespace sdft
