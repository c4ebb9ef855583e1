// The job's processes over MPI (communicator.h). Only this file calls MPI; without SDFT_HAVE_MPI
// the job is one process and messages cannot be sent.
#include "sdftrace/cluster/communicator.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <thread>

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

void Communicator::abort(int code) {
#if SDFT_HAVE_MPI
    if (m_mpi) MPI_Abort(MPI_COMM_WORLD, code);
#endif
    std::_Exit(code);
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
