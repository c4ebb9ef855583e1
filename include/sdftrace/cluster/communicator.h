// The processes of one job: MPI's world when sdftrace was started by mpirun (and built with MPI,
// SDFT_MPI), else this process alone. A thin layer over the few MPI calls the distributed render
// and bake need (docs/cluster.md): byte messages of any size between two ranks, polled so that a
// waiting rank does not spin a core its threads could use, and one collective that agrees on
// failure so that no rank is left waiting for one that has stopped.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace sdft {

using Bytes = std::vector<uint8_t>;

// Another rank failed (or this one, where the error was already reported to rank 0): the job
// stops. `message` names the rank; rank 0 prints it, the other ranks exit quietly.
class RankFailure : public std::runtime_error {
  public:
    RankFailure(const std::string& message, bool report)
        : std::runtime_error(message), m_report(report) {}
    // Whether this process should print the message (rank 0 only).
    bool report() const { return m_report; }

  private:
    bool m_report;
};

struct Message {
    int source = -1, tag = -1;
    Bytes bytes;
};

class Communicator {
  public:
    static constexpr int kAny = -1;

    // The job's communicator. init() is called once by main: it starts MPI only when the
    // environment says an MPI launcher started this process (OMPI_COMM_WORLD_SIZE, PMIX_RANK,
    // PMI_RANK); a plain run stays a single process without touching MPI.
    static Communicator& world();
    static void init(int& argc, char**& argv);
    // Ends MPI (at exit of main); a no-op without it.
    static void finalize();
    // Whether this build can run distributed (SDFT_MPI found MPI).
    static bool available();

    int rank() const { return m_rank; }
    int size() const { return m_size; }
    bool distributed() const { return m_size > 1; }
    bool root() const { return m_rank == 0; }
    // Ranks of this job on this machine (OMPI_COMM_WORLD_LOCAL_SIZE), to share its cores.
    int localSize() const { return m_localSize; }
    // This rank's index among them (OMPI_COMM_WORLD_LOCAL_RANK, MPI_LOCALRANKID; else its rank
    // modulo localSize), which picks its GPU (gpu_device.h, gpuOfLocalRank).
    int localRank() const { return m_localRank; }
    const std::string& host() const { return m_host; }
    // "rank 1 (node7)"
    std::string name(int rank) const;

    // Sends `size` bytes to rank `to` (blocking until the buffer may be reused). Messages of any
    // size: pieces under 2^31 bytes travel in order under the same tag.
    void send(int to, int tag, const void* data, size_t size);
    void send(int to, int tag, const Bytes& b) { send(to, tag, b.data(), b.size()); }
    // The next message from `from` with `tag` (kAny: any), waiting for it with short sleeps.
    Message receive(int from = kAny, int tag = kAny);
    // The next message if one has arrived.
    std::optional<Message> tryReceive(int from = kAny, int tag = kAny);

    // Collective, every rank calls it: each gives its error ("" for none). When any is non-empty
    // every rank throws RankFailure with the lowest failing rank's error, reported by rank 0.
    void agree(const std::string& error);

    // Collective: waits until every rank has arrived, polling with short sleeps (MPI's own barrier
    // spins a core that ranks still working on this machine could use).
    void barrier();
    // Collective: rank 0's `bytes` on every rank.
    void broadcast(Bytes& bytes);
    // Collective: every rank's `mine` (of any length), in rank order.
    std::vector<std::vector<uint64_t>> allGather(const std::vector<uint64_t>& mine);
    // Collective: sends out[r] to rank r (out has size() entries, each under 2 GiB); returns what
    // each rank sent to this one.
    std::vector<Bytes> allToAll(const std::vector<Bytes>& out);

    // Ends every rank now (the last resort when an error leaves other ranks waiting).
    [[noreturn]] void abort(int code);
    // Rank 0: the other ranks wait for nothing more from this one (their work is done), so an
    // error from here on is this process's alone.
    void setOthersDone() { m_othersDone = true; }
    bool othersDone() const { return m_othersDone; }

  private:
    Communicator() = default;
    Message receivePieces(int source, int tag, size_t firstPieceSize);
    int m_rank = 0, m_size = 1, m_localSize = 1, m_localRank = 0;
    bool m_mpi = false, m_othersDone = false;
    std::string m_host;
};

// A file that every rank writes parts of at offsets of its own (MPI-IO, so that it works on the
// parallel and network file systems of clusters; one process: plain positioned writes). Errors
// come back as text, so that the ranks can agree on them (Communicator::agree) instead of
// leaving the others waiting in a collective call.
class SharedFile {
  public:
    SharedFile() = default;
    SharedFile(const SharedFile&) = delete;
    SharedFile& operator=(const SharedFile&) = delete;
    ~SharedFile();  // closes the file if close() was not called (not collectively)
    // Collective: opens `path`, which exists (rank 0 made it), for writing. "" or the error.
    std::string open(Communicator& comm, const std::string& path);
    // Independent: writes `bytes` at `offset`. "" or the error.
    std::string writeAt(uint64_t offset, const void* data, size_t bytes);
    // Collective: flushes and closes. "" or the error.
    std::string close();

  private:
    void* m_handle = nullptr;  // MPI_File (MPI-IO) or null
    int m_fd = -1;             // one process
    bool m_mpi = false;
};

// How a waiting rank polls: sleeps of 20 us at first, doubling to 1 ms (a blocking MPI receive
// would spin a core that the rank's threads, or another rank on the machine, could use).
class Backoff {
  public:
    void wait();
    void reset() { m_us = 20; }

  private:
    int m_us = 20;
};

// Plain data in and out of byte messages.
class ByteWriter {
  public:
    template <class T>
    void put(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        append(&v, sizeof v);
    }
    void putString(const std::string& s) {
        put<uint64_t>(s.size());
        append(s.data(), s.size());
    }
    void append(const void* data, size_t n);
    Bytes& bytes() { return m_bytes; }

  private:
    Bytes m_bytes;
};

class ByteReader {
  public:
    explicit ByteReader(const Bytes& b) : m_data(b.data()), m_size(b.size()) {}
    template <class T>
    T get() {
        static_assert(std::is_trivially_copyable_v<T>);
        T v;
        read(&v, sizeof v);
        return v;
    }
    std::string getString();
    void read(void* out, size_t n);
    const uint8_t* take(size_t n);  // the next n bytes, in place
    size_t left() const { return m_size - m_at; }

  private:
    const uint8_t* m_data;
    size_t m_size, m_at = 0;
};

}  // namespace sdft
