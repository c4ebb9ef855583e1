// Rank 0 deals, the workers ask (work_farm.h). Messages between rank 0 and a worker, by tag:
//   0 -> w: Round (context), Chunk (first, last), RoundEnd, Quit, Abort;
//   w -> 0: Request (ready), Result (first, last, bytes; ready again), Finish (bytes), Error.
#include "sdftrace/cluster/work_farm.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <new>
#include <thread>
#include <utility>

#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/exec/progress.h"
#include "sdftrace/exec/thread_arena.h"

namespace sdft {

namespace {

enum Tag : int {
    kRound = 1,
    kChunk,
    kRoundEnd,
    kQuit,
    kAbort,
    kRequest = 10,
    kResult,
    kFinish,
    kError,
};

// Chunks shrink as the round's items run out (guided scheduling): large at first, so that few
// messages carry most of the work, and small at the end, so that the ranks finish together.
class Dealer {
  public:
    Dealer(const RoundPlan& p, int ranks) : m_plan(p), m_ranks(ranks) {}
    bool deal(int& first, int& last) {
        std::lock_guard lock(m_mutex);
        if (m_stopped || m_next >= m_plan.items) return false;
        const int left = m_plan.items - m_next;
        const int chunk = std::clamp((left + 2 * m_ranks - 1) / (2 * m_ranks), m_plan.minChunk,
                                     std::max(m_plan.minChunk, m_plan.maxChunk));
        first = m_next;
        last = m_next = std::min(m_plan.items, m_next + chunk);
        return true;
    }
    void stop() {
        std::lock_guard lock(m_mutex);
        m_stopped = true;
    }

  private:
    const RoundPlan& m_plan;
    const int m_ranks;
    std::mutex m_mutex;
    int m_next = 0;
    bool m_stopped = false;
};

[[noreturn]] void failSilently() { throw RankFailure("", false); }

// A test hook (docs/cluster.md, "Failures"): SDFTRACE_INJECT_FAILURE=R:N makes rank R fail at the
// start of its N-th chunk (N from 1; "R" alone: its first).
void injectedFailure(const Communicator& comm, int chunk) {
    const char* v = std::getenv("SDFTRACE_INJECT_FAILURE");
    if (!v) return;
    int rank = -1, at = 1;
    if (std::sscanf(v, "%d:%d", &rank, &at) < 1) return;
    if (rank == comm.rank() && chunk == at)
        throw std::runtime_error("injected failure (SDFTRACE_INJECT_FAILURE=" + std::string(v) +
                                 ")");
}

}  // namespace

std::string describeException(std::exception_ptr e) {
    try {
        std::rethrow_exception(e);
    } catch (const std::bad_alloc&) {
        return "out of memory (an allocation over the memory budget of " +
               formatBytes(memoryBudgetBytes()) +
               ", or the machine's memory is exhausted; see --max-memory)";
    } catch (const std::exception& x) {
        return x.what();
    } catch (...) {
        return "unknown error";
    }
}

int defaultRankThreads(const Communicator& comm) {
    const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    return std::max(1, std::min(resolveThreads(0), cores / std::max(1, comm.localSize())));
}

void together(Communicator& comm, const std::function<void()>& work) {
    if (!comm.distributed()) {
        work();
        return;
    }
    std::string error;
    try {
        work();
    } catch (...) {
        error = describeException(std::current_exception());
    }
    comm.agree(error);
}

WorkFarm::WorkFarm(Communicator& comm) : m_comm(comm) {}

WorkFarm::~WorkFarm() {
    if (!m_ended) stopWorkers(kAbort);
}

void WorkFarm::stopWorkers(int tag) {
    m_ended = true;
    for (int r = 1; r < m_comm.size(); ++r) m_comm.send(r, tag, nullptr, 0);
}

void WorkFarm::end() {
    if (!m_ended) stopWorkers(kQuit);
    m_comm.setOthersDone();
}

void WorkFarm::round(const RoundPlan& plan) {
    Dealer dealer(plan, m_comm.size());
    std::mutex failureMutex;
    std::string failure;  // the first failure, naming its rank
    std::vector<bool> failed(m_comm.size(), false);
    auto fail = [&](int rank, const std::string& what) {
        dealer.stop();
        std::lock_guard lock(failureMutex);
        if (failure.empty())
            failure = rank == 0 ? what : "rank " + std::to_string(rank) + ": " + what;
    };
    for (int r = 1; r < m_comm.size(); ++r) m_comm.send(r, kRound, plan.context);
    std::atomic<bool> localDone{false};
    std::thread local([&] {
        try {
            int first = 0, last = 0;
            while (dealer.deal(first, last)) {
                plan.local(first, last);
                if (plan.progress) plan.progress->advance(static_cast<uint64_t>(last - first));
            }
        } catch (...) {
            fail(0, describeException(std::current_exception()));
        }
        localDone = true;
    });
    auto reply = [&](int rank) {
        int first = 0, last = 0;
        if (dealer.deal(first, last)) {
            const int range[2] = {first, last};
            m_comm.send(rank, kChunk, range, sizeof range);
        } else {
            m_comm.send(rank, kRoundEnd, nullptr, 0);
        }
    };
    int active = m_comm.size() - 1;
    Backoff backoff;
    while (active > 0 || !localDone) {
        std::optional<Message> m = m_comm.tryReceive();
        if (!m) {
            backoff.wait();
            continue;
        }
        backoff.reset();
        const int r = m->source;
        try {
            ByteReader in(m->bytes);
            switch (m->tag) {
                case kRequest:
                    reply(r);
                    break;
                case kResult: {
                    const int first = in.get<int>(), last = in.get<int>();
                    if (plan.onResult) plan.onResult(r, first, last, in);
                    if (plan.progress) plan.progress->advance(static_cast<uint64_t>(last - first));
                    reply(r);
                    break;
                }
                case kFinish:
                    --active;
                    if (plan.onFinish) plan.onFinish(r, m->bytes);
                    break;
                case kError:
                    --active;
                    failed[r] = true;
                    fail(r, in.getString());
                    break;
                default:
                    fail(0, "cluster: unexpected message " + std::to_string(m->tag) +
                                " from rank " + std::to_string(r));
            }
        } catch (...) {
            // Rank 0 could not take this result (out of memory, say): the round ends as a failure;
            // the sender is still answered so that it does not wait.
            fail(0, describeException(std::current_exception()));
            if (m->tag == kResult) reply(r);
        }
    }
    local.join();
    if (failure.empty()) return;
    m_ended = true;
    for (int r = 1; r < m_comm.size(); ++r)
        if (!failed[r]) m_comm.send(r, kAbort, nullptr, 0);
    throw RankFailure(failure, true);
}

void serveRounds(Communicator& comm,
                 const std::function<std::unique_ptr<RoundWorker>(const Bytes& context)>& start,
                 const std::function<void()>& prepare) {
    // An error here is rank 0's to report; this rank stops.
    auto reportAndStop = [&] {
        ByteWriter w;
        w.putString(describeException(std::current_exception()));
        comm.send(0, kError, w.bytes());
        failSilently();
    };
    std::exception_ptr deferred;  // prepare's error, reported when the next round starts
    int chunks = 0;
    for (;;) {
        if (prepare) {
            try {
                prepare();
            } catch (...) {
                deferred = std::current_exception();
            }
        }
        Message m = comm.receive(0);
        if (m.tag == kQuit) return;
        if (m.tag != kRound) failSilently();  // kAbort (or anything unexpected)
        std::unique_ptr<RoundWorker> worker;
        try {
            if (deferred) std::rethrow_exception(std::exchange(deferred, nullptr));
            worker = start(m.bytes);
        } catch (...) {
            reportAndStop();
        }
        comm.send(0, kRequest, nullptr, 0);
        for (;;) {
            Message c = comm.receive(0);
            if (c.tag == kChunk) {
                ByteReader in(c.bytes);
                const int first = in.get<int>(), last = in.get<int>();
                ByteWriter out;
                out.put(first);
                out.put(last);
                try {
                    injectedFailure(comm, ++chunks);
                    worker->run(first, last, out);
                } catch (...) {
                    reportAndStop();
                }
                comm.send(0, kResult, out.bytes());
            } else if (c.tag == kRoundEnd) {
                Bytes f;
                try {
                    f = worker->finish();
                } catch (...) {
                    reportAndStop();
                }
                comm.send(0, kFinish, f);
                break;
            } else {
                failSilently();
            }
        }
    }
}

}  // namespace sdft
