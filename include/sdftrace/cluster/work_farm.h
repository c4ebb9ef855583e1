// Dynamic work distribution across the job's ranks (docs/cluster.md): rank 0 deals items
// [0, n) in chunks to whichever rank asks next, itself included (on a second thread while its main
// thread serves the others), so a slow node takes fewer chunks instead of holding the job back.
// A job is a sequence of rounds (one per frame of a render, say); each round starts with a
// context that every worker receives (the frame's view). Any rank's failure ends the job on every
// rank: the failing worker reports its error to rank 0, which stops dealing, lets the others
// finish their chunk, tells them to stop and throws the error (RankFailure) — no rank is left
// waiting and rank 0 writes nothing.
#pragma once

#include <functional>
#include <memory>

#include "sdftrace/cluster/communicator.h"

namespace sdft {

class Progress;

// What a worker does in one round.
class RoundWorker {
  public:
    virtual ~RoundWorker() = default;
    // Items [first, last): their result, written to `out` for rank 0.
    virtual void run(int first, int last, ByteWriter& out) = 0;
    // After the round's last chunk: what else rank 0 needs (statistics).
    virtual Bytes finish() { return {}; }
};

struct RoundPlan {
    Bytes context;  // sent to every worker at the start
    int items = 0;
    // Rank 0's own share, on its worker thread: items [first, last).
    std::function<void(int first, int last)> local;
    // On rank 0's main thread, as each worker's chunk arrives (disjoint from the local share).
    std::function<void(int rank, int first, int last, ByteReader& result)> onResult;
    // A worker's finish() bytes.
    std::function<void(int rank, const Bytes& result)> onFinish;
    Progress* progress = nullptr;  // advanced by the items done, on any rank
};

// Rank 0's side of a job. Its destructor ends the job: normally after end(), else (an exception
// on rank 0 between rounds) it tells every worker to stop with a failure.
class WorkFarm {
  public:
    explicit WorkFarm(Communicator& comm);
    ~WorkFarm();
    WorkFarm(const WorkFarm&) = delete;
    WorkFarm& operator=(const WorkFarm&) = delete;

    // One round; throws RankFailure if a rank failed (the job is then over).
    void round(const RoundPlan& plan);
    int ranks() const { return m_comm.size(); }
    // Every worker leaves its serve() loop successfully.
    void end();

  private:
    void stopWorkers(int tag);
    Communicator& m_comm;
    bool m_ended = false;
};

// A worker's side: serves rounds until rank 0 ends the job. `start` makes the round's worker from
// its context. Returns when the job ended normally; throws RankFailure (not to be printed: rank 0
// reports) when any rank failed, this one included. `prepare`, if set, runs before each round is
// awaited (at the start, and once a round's results are sent) while rank 0 gets the next round
// ready: work the next round will need. Its error is reported when that round starts.
void serveRounds(Communicator& comm,
                 const std::function<std::unique_ptr<RoundWorker>(const Bytes& context)>& start,
                 const std::function<void()>& prepare = nullptr);

// A rank's threads under mpirun when none are asked for: its share of the machine's cores (the
// ranks on one machine split them).
int defaultRankThreads(const Communicator& comm);

// The one-line message of an exception, as main prints it (out of memory spelled out).
std::string describeException(std::exception_ptr e);

// Runs `work` on every rank and then agrees (Communicator::agree): when it threw on any rank,
// every rank throws RankFailure. Single-process: `work`'s exceptions pass through unchanged.
void together(Communicator& comm, const std::function<void()>& work);

}  // namespace sdft
