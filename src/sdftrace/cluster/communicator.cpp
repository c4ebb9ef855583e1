// The job's processes over MPI (communicator.h). Only this file calls MPI; without SDFT_HAVE_MPI
// the job is one process and messages cannot be sent.
#include "sdftrace/cluster/communicator.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <thread>

#include "sdftrace/core/memory_budget.h"

#if SDFT_HAVE_MPI
#include <mpi.h>
#endif

namespace sdft {

namespace {

// Pieces of one message: MPI counts are ints.
constexpr size_t kPiece = size_t(1) << 30;

bool launchedByMpi() {
    for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
        if (std::getenv(v)) return true;
    return false;
}

int envInt(const char* name, int fallback, int least = 1) {
    const char* v = std::getenv(name);
    if (!v) return fallback;
    char* end = nullptr;
    long n = std::strtol(v, &end, 10);
    return end != v && n >= least && n < (1 << 20) ? static_cast<int>(n) : fallback;
}

}  // namespace

Communicator& Communicator::world() {
    static Communicator c;
    return c;
}

bool Communicator::available() { return SDFT_HAVE_MPI != 0; }

void Communicator::init(int& argc, char**& argv) {
    Communicator& c = world();
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    c.m_host = host;
#if SDFT_HAVE_MPI
    if (!launchedByMpi()) return;
    int provided = 0;
    // Rank 0's main thread talks to the other ranks while another renders: only the main thread
    // calls MPI.
    MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_ARE_FATAL);
    MPI_Comm_rank(MPI_COMM_WORLD, &c.m_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &c.m_size);
    c.m_localSize = envInt("OMPI_COMM_WORLD_LOCAL_SIZE", envInt("MPI_LOCALNRANKS", 1));
    c.m_localRank = envInt("OMPI_COMM_WORLD_LOCAL_RANK",
                           envInt("MPI_LOCALRANKID", c.m_rank % c.m_localSize, 0), 0);
    c.m_mpi = true;
    // The ranks on this machine share its memory as they share its cores.
    setMemorySharers(c.m_localSize);
#else
    (void)argc;
    (void)argv;
    (void)launchedByMpi;
    (void)envInt;
#endif
}

void Communicator::finalize() {
#if SDFT_HAVE_MPI
    Communicator& c = world();
    if (c.m_mpi) {
        c.m_mpi = false;
        MPI_Finalize();
    }
#endif
}

std::string Communicator::name(int rank) const {
    return "rank " + std::to_string(rank) + (rank == m_rank ? " (" + m_host + ")" : "");
}

void Communicator::send(int to, int tag, const void* data, size_t size) {
#if SDFT_HAVE_MPI
    if (!m_mpi) throw std::logic_error("Communicator::send without MPI");
    // The first piece leads with the total size.
    const auto* p = static_cast<const uint8_t*>(data);
    const size_t first = std::min(size, kPiece - sizeof(uint64_t));
    Bytes head(sizeof(uint64_t) + first);
    const uint64_t total = size;
    std::memcpy(head.data(), &total, sizeof total);
    if (first) std::memcpy(head.data() + sizeof total, p, first);
    MPI_Send(head.data(), static_cast<int>(head.size()), MPI_BYTE, to, tag, MPI_COMM_WORLD);
    for (size_t at = first; at < size; at += kPiece) {
        const size_t n = std::min(kPiece, size - at);
        MPI_Send(p + at, static_cast<int>(n), MPI_BYTE, to, tag, MPI_COMM_WORLD);
    }
#else
    (void)to, (void)tag, (void)data, (void)size;
    throw std::logic_error("Communicator::send in a build without MPI");
#endif
}

Message Communicator::receivePieces(int source, int tag, size_t firstPieceSize) {
    Message m;
    m.source = source;
    m.tag = tag;
#if SDFT_HAVE_MPI
    Bytes head(firstPieceSize);
    MPI_Recv(head.data(), static_cast<int>(head.size()), MPI_BYTE, source, tag, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
    uint64_t total = 0;
    std::memcpy(&total, head.data(), sizeof total);
    m.bytes.resize(total);
    const size_t first = head.size() - sizeof total;
    if (first) std::memcpy(m.bytes.data(), head.data() + sizeof total, first);
    head = Bytes();
    for (size_t at = first; at < total; at += kPiece) {
        const size_t n = std::min<size_t>(kPiece, total - at);
        MPI_Recv(m.bytes.data() + at, static_cast<int>(n), MPI_BYTE, source, tag, MPI_COMM_WORLD,
                 MPI_STATUS_IGNORE);
    }
#else
    (void)firstPieceSize;
#endif
    return m;
}

std::optional<Message> Communicator::tryReceive(int from, int tag) {
#if SDFT_HAVE_MPI
    if (!m_mpi) throw std::logic_error("Communicator::tryReceive without MPI");
    int flag = 0;
    MPI_Status status;
    MPI_Iprobe(from == kAny ? MPI_ANY_SOURCE : from, tag == kAny ? MPI_ANY_TAG : tag,
               MPI_COMM_WORLD, &flag, &status);
    if (!flag) return std::nullopt;
    int count = 0;
    MPI_Get_count(&status, MPI_BYTE, &count);
    return receivePieces(status.MPI_SOURCE, status.MPI_TAG, static_cast<size_t>(count));
#else
    (void)from, (void)tag;
    throw std::logic_error("Communicator::tryReceive in a build without MPI");
#endif
}

Message Communicator::receive(int from, int tag) {
    Backoff backoff;
    for (;;) {
        if (std::optional<Message> m = tryReceive(from, tag)) return std::move(*m);
        backoff.wait();
    }
}

void Communicator::agree(const std::string& error) {
    if (!distributed()) {
        if (!error.empty()) throw RankFailure(error, true);
        return;
    }
#if SDFT_HAVE_MPI
    // The lowest failing rank (size if none), then its message from it.
    int mine = error.empty() ? m_size : m_rank, lowest = m_size;
    MPI_Allreduce(&mine, &lowest, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (lowest == m_size) return;
    uint64_t length = lowest == m_rank ? error.size() : 0;
    MPI_Bcast(&length, 1, MPI_UINT64_T, lowest, MPI_COMM_WORLD);
    std::string text = lowest == m_rank ? error : std::string(length, '\0');
    MPI_Bcast(text.data(), static_cast<int>(length), MPI_CHAR, lowest, MPI_COMM_WORLD);
    throw RankFailure(lowest == 0 ? text : "rank " + std::to_string(lowest) + ": " + text,
                      m_rank == 0);
#endif
}

void Communicator::barrier() {
#if SDFT_HAVE_MPI
    if (!m_mpi) return;
    MPI_Request request;
    MPI_Ibarrier(MPI_COMM_WORLD, &request);
    Backoff backoff;
    for (int done = 0;;) {
        MPI_Test(&request, &done, MPI_STATUS_IGNORE);
        if (done) return;
        backoff.wait();
    }
#endif
}

void Communicator::broadcast(Bytes& bytes) {
#if SDFT_HAVE_MPI
    if (!m_mpi) return;
    uint64_t n = bytes.size();
    MPI_Bcast(&n, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
    bytes.resize(n);
    for (size_t at = 0; at < n; at += kPiece)
        MPI_Bcast(bytes.data() + at, static_cast<int>(std::min<size_t>(kPiece, n - at)), MPI_BYTE,
                  0, MPI_COMM_WORLD);
#else
    (void)bytes;
#endif
}

std::vector<std::vector<uint64_t>> Communicator::allGather(const std::vector<uint64_t>& mine) {
    std::vector<std::vector<uint64_t>> all(static_cast<size_t>(m_size));
#if SDFT_HAVE_MPI
    if (m_mpi) {
        const int count = static_cast<int>(mine.size());
        std::vector<int> counts(all.size()), displs(all.size(), 0);
        MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
        for (size_t r = 1; r < all.size(); ++r) displs[r] = displs[r - 1] + counts[r - 1];
        std::vector<uint64_t> flat(static_cast<size_t>(displs.back() + counts.back()));
        MPI_Allgatherv(mine.data(), count, MPI_UINT64_T, flat.data(), counts.data(), displs.data(),
                       MPI_UINT64_T, MPI_COMM_WORLD);
        for (size_t r = 0; r < all.size(); ++r)
            all[r].assign(flat.begin() + displs[r], flat.begin() + displs[r] + counts[r]);
        return all;
    }
#endif
    all[0] = mine;
    return all;
}

std::vector<Bytes> Communicator::allToAll(const std::vector<Bytes>& out) {
    if (out.size() != static_cast<size_t>(m_size))
        throw std::logic_error("Communicator::allToAll: one buffer per rank");
#if SDFT_HAVE_MPI
    if (m_mpi) {
        const size_t n = out.size();
        std::vector<int> sendCounts(n), sendDispls(n, 0), recvCounts(n), recvDispls(n, 0);
        Bytes flat;
        for (size_t r = 0; r < n; ++r) {
            if (out[r].size() >= kPiece) throw std::logic_error("Communicator::allToAll: 1 GiB");
            sendCounts[r] = static_cast<int>(out[r].size());
            sendDispls[r] = static_cast<int>(flat.size());
            flat.insert(flat.end(), out[r].begin(), out[r].end());
        }
        MPI_Alltoall(sendCounts.data(), 1, MPI_INT, recvCounts.data(), 1, MPI_INT, MPI_COMM_WORLD);
        size_t total = 0;
        for (size_t r = 0; r < n; ++r) {
            recvDispls[r] = static_cast<int>(total);
            total += static_cast<size_t>(recvCounts[r]);
        }
        if (total >= kPiece) throw std::logic_error("Communicator::allToAll: 1 GiB");
        Bytes in(total);
        MPI_Alltoallv(flat.data(), sendCounts.data(), sendDispls.data(), MPI_BYTE, in.data(),
                      recvCounts.data(), recvDispls.data(), MPI_BYTE, MPI_COMM_WORLD);
        std::vector<Bytes> got(n);
        for (size_t r = 0; r < n; ++r)
            got[r].assign(in.begin() + recvDispls[r], in.begin() + recvDispls[r] + recvCounts[r]);
        return got;
    }
#endif
    return out;
}

void Communicator::abort(int code) {
#if SDFT_HAVE_MPI
    if (m_mpi) MPI_Abort(MPI_COMM_WORLD, code);
#endif
    std::_Exit(code);
}

SharedFile::~SharedFile() {
#if SDFT_HAVE_MPI
    if (m_handle) {
        auto* f = static_cast<MPI_File*>(m_handle);
        delete f;  // not closed collectively: the job is ending
    }
#endif
    if (m_fd >= 0) ::close(m_fd);
}

std::string SharedFile::open(Communicator& comm, const std::string& path) {
#if SDFT_HAVE_MPI
    if (comm.distributed()) {
        auto* f = new MPI_File;
        const int rc =
            MPI_File_open(MPI_COMM_WORLD, path.c_str(), MPI_MODE_WRONLY, MPI_INFO_NULL, f);
        if (rc != MPI_SUCCESS) {
            delete f;
            char text[MPI_MAX_ERROR_STRING];
            int n = 0;
            MPI_Error_string(rc, text, &n);
            return path + ": cannot open for writing (" + std::string(text, n) + ")";
        }
        m_handle = f;
        m_mpi = true;
        return "";
    }
#endif
    (void)comm;
    m_fd = ::open(path.c_str(), O_WRONLY);
    return m_fd < 0 ? path + ": cannot open for writing (" + std::strerror(errno) + ")" : "";
}

std::string SharedFile::writeAt(uint64_t offset, const void* data, size_t bytes) {
    const auto* p = static_cast<const char*>(data);
#if SDFT_HAVE_MPI
    if (m_mpi) {
        auto* f = static_cast<MPI_File*>(m_handle);
        for (size_t at = 0; at < bytes; at += kPiece) {
            const int n = static_cast<int>(std::min(kPiece, bytes - at));
            MPI_Status status;
            const int rc = MPI_File_write_at(*f, static_cast<MPI_Offset>(offset + at), p + at, n,
                                             MPI_BYTE, &status);
            int wrote = 0;
            MPI_Get_count(&status, MPI_BYTE, &wrote);
            if (rc != MPI_SUCCESS || wrote != n) return "write failed (MPI-IO)";
        }
        return "";
    }
#endif
    for (size_t at = 0; at < bytes;) {
        const ssize_t n = ::pwrite(m_fd, p + at, bytes - at, static_cast<off_t>(offset + at));
        if (n <= 0) return std::string("write failed (") + std::strerror(n < 0 ? errno : EIO) + ")";
        at += static_cast<size_t>(n);
    }
    return "";
}

std::string SharedFile::close() {
    std::string error;
#if SDFT_HAVE_MPI
    if (m_mpi && m_handle) {
        auto* f = static_cast<MPI_File*>(m_handle);
        if (MPI_File_close(f) != MPI_SUCCESS) error = "close failed (MPI-IO)";
        delete f;
        m_handle = nullptr;
    }
#endif
    if (m_fd >= 0) {
        if (::close(m_fd) != 0) error = std::string("close failed (") + std::strerror(errno) + ")";
        m_fd = -1;
    }
    return error;
}

void Backoff::wait() {
    std::this_thread::sleep_for(std::chrono::microseconds(m_us));
    m_us = std::min(m_us * 2, 1000);
}

void ByteWriter::append(const void* data, size_t n) {
    const auto* p = static_cast<const uint8_t*>(data);
    m_bytes.insert(m_bytes.end(), p, p + n);
}

void ByteReader::read(void* out, size_t n) { std::memcpy(out, take(n), n); }

const uint8_t* ByteReader::take(size_t n) {
    if (n > m_size - m_at) throw std::runtime_error("cluster message: truncated");
    const uint8_t* p = m_data + m_at;
    m_at += n;
    return p;
}

std::string ByteReader::getString() {
    const auto n = get<uint64_t>();
    const uint8_t* p = take(n);
    return std::string(reinterpret_cast<const char*>(p), n);
}

}  // namespace sdft
