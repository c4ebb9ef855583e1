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
        const int chunk = (left + 2 * m_ranks - 1) / (2 * m_ranks);
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
// start of its N-th chunk (N from 1; "R" alone: its first), or at the end of a round if rank 0 has
// dealt every chunk before R reached its N-th (a small job on a busy machine), so that the failure
// always happens. roundEnd: called when a round ends, with the chunks R has served so far.
void injectedFailure(const Communicator& comm, int chunk, bool roundEnd = false) {
    const char* v = std::getenv("SDFTRACE_INJECT_FAILURE");
    if (!v) return;
    int rank = -1, at = 1;
    if (std::sscanf(v, "%d:%d", &rank, &at) < 1) return;
    if (rank == comm.rank() && (chunk == at || (roundEnd && chunk < at)))
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

namespace {

// Rank 0's side of one round: the dealer, the first failure, and the answers to the workers.
class RoundServer {
  public:
    RoundServer(Communicator& comm, const RoundPlan& plan)
        : m_comm(comm), m_plan(plan), m_dealer(plan, comm.size()), m_failed(comm.size(), false) {}

    // Rank 0's own share, on its second thread.
    void runLocalShare() {
        try {
            int first = 0, last = 0;
            while (m_dealer.deal(first, last)) {
                m_plan.local(first, last);
                if (m_plan.progress) m_plan.progress->advance(static_cast<uint64_t>(last - first));
            }
        } catch (...) {
            fail(0, describeException(std::current_exception()));
        }
    }

    // One worker message; false once that worker is done with the round.
    bool handle(const Message& m) {
        const int r = m.source;
        try {
            ByteReader in(m.bytes);
            switch (m.tag) {
                case kRequest:
                    reply(r);
                    return true;
                case kResult: {
                    const int first = in.get<int>(), last = in.get<int>();
                    if (m_plan.onResult) m_plan.onResult(r, first, last, in);
                    if (m_plan.progress)
                        m_plan.progress->advance(static_cast<uint64_t>(last - first));
                    reply(r);
                    return true;
                }
                case kFinish:
                    if (m_plan.onFinish) m_plan.onFinish(r, m.bytes);
                    return false;
                case kError:
                    m_failed[r] = true;
                    fail(r, in.getString());
                    return false;
                default:
                    fail(0, "cluster: unexpected message " + std::to_string(m.tag) + " from rank " +
                                std::to_string(r));
                    return true;
            }
        } catch (...) {
            // Rank 0 could not take this result (out of memory, say): the round ends as a failure;
            // the sender is still answered so that it does not wait.
            fail(0, describeException(std::current_exception()));
            if (m.tag == kResult) reply(r);
            return m.tag != kFinish && m.tag != kError;
        }
    }

    const std::string& failure() const { return m_failure; }
    bool failed(int rank) const { return m_failed[rank]; }

  private:
    void fail(int rank, const std::string& what) {
        m_dealer.stop();
        std::lock_guard lock(m_failureMutex);
        if (m_failure.empty())
            m_failure = rank == 0 ? what : "rank " + std::to_string(rank) + ": " + what;
    }
    // The next chunk, or the end of the round.
    void reply(int rank) {
        int range[2] = {0, 0};
        if (m_dealer.deal(range[0], range[1]))
            m_comm.send(rank, kChunk, range, sizeof range);
        else
            m_comm.send(rank, kRoundEnd, nullptr, 0);
    }

    Communicator& m_comm;
    const RoundPlan& m_plan;
    Dealer m_dealer;
    std::mutex m_failureMutex;
    std::string m_failure;  // the first failure, naming its rank
    std::vector<bool> m_failed;
};

}  // namespace

void WorkFarm::round(const RoundPlan& plan) {
    RoundServer server(m_comm, plan);
    for (int r = 1; r < m_comm.size(); ++r) m_comm.send(r, kRound, plan.context);
    std::atomic<bool> localDone{false};
    std::thread local([&] {
        server.runLocalShare();
        localDone = true;
    });
    int active = m_comm.size() - 1;
    Backoff backoff;
    while (active > 0 || !localDone) {
        if (std::optional<Message> m = m_comm.tryReceive()) {
            backoff.reset();
            if (!server.handle(*m)) --active;
        } else {
            backoff.wait();
        }
    }
    local.join();
    if (server.failure().empty()) return;
    m_ended = true;
    for (int r = 1; r < m_comm.size(); ++r)
        if (!server.failed(r)) m_comm.send(r, kAbort, nullptr, 0);
    throw RankFailure(server.failure(), true);
}

namespace {

// A worker's failure: reported to rank 0, which reports it; this rank stops.
[[noreturn]] void reportAndStop(Communicator& comm) {
    ByteWriter w;
    w.putString(describeException(std::current_exception()));
    comm.send(0, kError, w.bytes());
    failSilently();
}

// One round's chunks, until rank 0 says the round is over.
void serveChunks(Communicator& comm, RoundWorker& worker, int& chunks) {
    comm.send(0, kRequest, nullptr, 0);
    for (;;) {
        const Message c = comm.receive(0);
        if (c.tag == kRoundEnd) {
            try {
                injectedFailure(comm, chunks, true);
            } catch (...) {
                reportAndStop(comm);
            }
            break;
        }
        if (c.tag != kChunk) failSilently();  // kAbort
        ByteReader in(c.bytes);
        const int first = in.get<int>(), last = in.get<int>();
        ByteWriter out;
        out.put(first);
        out.put(last);
        try {
            injectedFailure(comm, ++chunks);
            worker.run(first, last, out);
        } catch (...) {
            reportAndStop(comm);
        }
        comm.send(0, kResult, out.bytes());
    }
    Bytes finished;
    try {
        finished = worker.finish();
    } catch (...) {
        reportAndStop(comm);
    }
    comm.send(0, kFinish, finished);
}

}  // namespace

void serveRounds(Communicator& comm,
                 const std::function<std::unique_ptr<RoundWorker>(const Bytes& context)>& start,
                 const std::function<void()>& prepare) {
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
        const Message m = comm.receive(0);
        if (m.tag == kQuit) return;
        if (m.tag != kRound) failSilently();  // kAbort (or anything unexpected)
        std::unique_ptr<RoundWorker> worker;
        try {
            if (deferred) std::rethrow_exception(std::exchange(deferred, nullptr));
            worker = start(m.bytes);
        } catch (...) {
            reportAndStop(comm);
        }
        serveChunks(comm, *worker, chunks);
    }
}

}  // namespace sdft
