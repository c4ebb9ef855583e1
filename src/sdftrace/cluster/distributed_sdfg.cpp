// The sparse exact bake written by every rank into one .sdfg (distributed_bake.h:
// bakeExactToSdfg; docs/cluster.md, "Bakes"). Version 4's sections (docs/file-formats.md) are
// all in block or tile order, so with slabs that start on tile layers each rank's part of every
// section is one run of bytes: the tile kinds and own pages of its tile layers, its surface
// blocks' own samples, apron masks and kept apron samples. Chunks are cut at multiples of the
// chunk size across the whole section, exactly as one process cuts them; a chunk is compressed by
// the rank holding its first byte, with the bytes of the ranks after it that it spans.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "sdftrace/bake/exact_slab.h"
#include "sdftrace/cluster/distributed_bake.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/exec/thread_arena.h"
#include "sdftrace/field/block_table.h"
#include "sdftrace/io/atomic_file.h"
#include "sdftrace/io/sdfg_io.h"
#include "sdftrace/io/sdfg_layout.h"

namespace sdft {

namespace {

using Clock = std::chrono::steady_clock;
constexpr int kSections = 5;  // tile kinds, own pages, own samples, apron masks, kept samples

double since(Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
}

// Every rank calls it at the same points: waits for all (polling), then agrees on the errors.
void checkpoint(Communicator& comm, const std::string& error) {
    comm.barrier();
    comm.agree(error);
}

// docs/cluster.md's test hooks: SDFTRACE_INJECT_FAILURE=R (or R:N) makes rank R fail in its
// slab with an error; R:kill makes it die there (SIGKILL, as the kernel's OOM killer does), and
// R:kill-write die while the ranks write the file.
void injectedFailure(const Communicator& comm, bool writing) {
    const char* v = std::getenv("SDFTRACE_INJECT_FAILURE");
    int rank = -1;
    char what[16] = {};
    if (!v || std::sscanf(v, "%d:%15s", &rank, what) < 1 || rank != comm.rank()) return;
    const std::string how = what;
    if (how == (writing ? "kill-write" : "kill")) std::raise(SIGKILL);
    if (!writing && how.rfind("kill", 0) != 0)
        throw std::runtime_error("injected failure (SDFTRACE_INJECT_FAILURE=" + std::string(v) +
                                 ")");
}

// This rank's part of the file: its sections' bytes and what the header counts.
struct Part {
    SlabSections slab;
    std::vector<uint8_t> tileKinds, ownPages;
    uint64_t inside = 0, outside = 0;
    const char* data[kSections] = {};
    uint64_t bytes[kSections] = {};
};

constexpr bool kFloats[kSections] = {false, false, true, false, true};

// The block table of the slab's layers (tiles are the whole grid's: the slab starts on a tile
// layer) as version 4 stores it.
void blockTableOf(Part& p, const int nb[3]) {
    const int layers = p.slab.slab.last - p.slab.slab.first;
    if (layers <= 0) return;
    const int blocks[3] = {nb[0], nb[1], layers};
    for (uint8_t f : p.slab.flags) {
        p.inside += f == static_cast<uint8_t>(BlockFlag::Inside);
        p.outside += f == static_cast<uint8_t>(BlockFlag::Outside);
    }
    BlockTable t = BlockTable::fromDense(blocks, p.slab.flags, "exact bake");
    p.slab.flags = std::vector<uint8_t>();
    p.tileKinds.resize(t.tilePage.size());
    for (size_t i = 0; i < t.tilePage.size(); ++i)
        p.tileKinds[i] = static_cast<uint8_t>(std::min(t.tilePage[i], kFirstOwnPage));
    p.ownPages.assign(t.flags.begin() + kFirstOwnPage * kPageEntries, t.flags.end());
}

void sectionsOf(Part& p) {
    const auto set = [&](int s, const void* d, uint64_t n) {
        p.data[s] = static_cast<const char*>(d);
        p.bytes[s] = n;
    };
    set(0, p.tileKinds.data(), p.tileKinds.size());
    set(1, p.ownPages.data(), p.ownPages.size());
    set(2, p.slab.own.data(), p.slab.own.size() * sizeof(float));
    set(3, p.slab.apronMasks.data(), p.slab.apronMasks.size() * sizeof(uint64_t));
    set(4, p.slab.kept.data(), p.slab.kept.size() * sizeof(float));
}

// Where every rank's part of every section lies in the section, and the chunks.
struct Layout {
    int ranks = 0;
    std::vector<uint64_t> offset, bytes;  // [rank * kSections + section]
    uint64_t total[kSections] = {};
    uint64_t firstChunk[kSections + 1] = {};  // global chunk numbers by section
    uint64_t at(int r, int s) const { return offset[static_cast<size_t>(r) * kSections + s]; }
    uint64_t size(int r, int s) const { return bytes[static_cast<size_t>(r) * kSections + s]; }
    // The rank holding byte `b` of section s (its part is not empty).
    int holder(int s, uint64_t b) const {
        for (int r = 0; r < ranks; ++r)
            if (size(r, s) && b >= at(r, s) && b < at(r, s) + size(r, s)) return r;
        throw std::logic_error("distributed .sdfg: no rank holds a byte");
    }
};

Layout layoutOf(const std::vector<std::vector<uint64_t>>& sizes) {
    Layout L;
    L.ranks = static_cast<int>(sizes.size());
    for (int r = 0; r < L.ranks; ++r)
        for (int s = 0; s < kSections; ++s) {
            L.offset.push_back(L.total[s]);
            L.bytes.push_back(sizes[r][s]);
            L.total[s] += sizes[r][s];
        }
    for (int s = 0; s < kSections; ++s)
        L.firstChunk[s + 1] =
            L.firstChunk[s] + (L.total[s] + kSdfgChunkBytes - 1) / kSdfgChunkBytes;
    return L;
}

// A part's head: its bytes before its first chunk boundary, which belong to a chunk that starts
// in an earlier rank's part. Sent to that rank, section by section.
uint64_t headBytes(const Layout& L, int r, int s) {
    const uint64_t o = L.at(r, s), n = L.size(r, s);
    if (!n || o % kSdfgChunkBytes == 0) return 0;
    return std::min(n, kSdfgChunkBytes - o % kSdfgChunkBytes);
}

std::vector<Bytes> headsOut(const Layout& L, const Part& p, int me) {
    std::vector<Bytes> out(static_cast<size_t>(L.ranks));
    for (int s = 0; s < kSections; ++s) {
        const uint64_t n = headBytes(L, me, s);
        if (!n) continue;
        const uint64_t start = L.at(me, s) / kSdfgChunkBytes * kSdfgChunkBytes;
        Bytes& to = out[static_cast<size_t>(L.holder(s, start))];
        to.insert(to.end(), p.data[s], p.data[s] + n);
    }
    return out;
}

// One chunk this rank compresses: section s, global chunk number, its bytes (in this rank's part,
// or gathered where the chunk spans later ranks' parts).
struct OwnChunk {
    int section;
    uint64_t number;
    const char* data;
    uint64_t size;
    Bytes gathered;
    std::vector<char> packed;
};

// The chunks that start in this rank's parts, each with the heads of the later ranks it spans.
std::vector<OwnChunk> ownChunks(const Layout& L, const Part& p, int me,
                                const std::vector<Bytes>& heads) {
    std::vector<size_t> read(heads.size(), 0);  // per sender, bytes of its heads consumed
    std::vector<OwnChunk> out;
    for (int s = 0; s < kSections; ++s) {
        const uint64_t o = L.at(me, s), n = L.size(me, s);
        if (!n) continue;
        for (uint64_t c = (o + kSdfgChunkBytes - 1) / kSdfgChunkBytes * kSdfgChunkBytes; c < o + n;
             c += kSdfgChunkBytes) {
            const uint64_t end = std::min(c + kSdfgChunkBytes, L.total[s]);
            OwnChunk ch{s, L.firstChunk[s] + c / kSdfgChunkBytes, p.data[s] + (c - o), end - c, {},
                        {}};
            const uint64_t mine = std::min(end, o + n) - c;
            if (mine == end - c) {
                out.push_back(std::move(ch));
                continue;
            }
            ch.gathered.assign(ch.data, ch.data + mine);
            // The rest from the ranks after this one, in order (their heads for section s).
            for (int r = me + 1; ch.gathered.size() < end - c && r < L.ranks; ++r) {
                const uint64_t h = headBytes(L, r, s);
                if (!h) continue;
                const Bytes& from = heads[static_cast<size_t>(r)];
                if (read[r] + h > from.size())
                    throw std::logic_error("distributed .sdfg: a rank sent too few bytes");
                ch.gathered.insert(ch.gathered.end(), from.begin() + read[r],
                                   from.begin() + read[r] + h);
                read[r] += h;
            }
            if (ch.gathered.size() != end - c)
                throw std::logic_error("distributed .sdfg: a chunk was not gathered whole");
            ch.data = reinterpret_cast<const char*>(ch.gathered.data());
            out.push_back(std::move(ch));
        }
    }
    return out;
}

void compressChunks(std::vector<OwnChunk>& chunks, int level, int threads,
                    const std::string& path) {
    ThreadArena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(size_t(0), chunks.size(), [&](size_t i) {
            std::vector<char> scratch;
            OwnChunk& c = chunks[i];
            c.packed = compressSdfgChunk(c.data, c.size, kFloats[c.section], level, scratch, path);
            c.gathered = Bytes();
        });
    });
}

// The slab's bake with the exchange of the layer flags past each slab (a collective step).
Part bakePart(Communicator& comm, const TriangleMesh& mesh, const MeshBakeOptions& o,
              const GridShape& shape, const std::vector<BlockSlab>& slabs, ExactBakeStats& stats) {
    const int me = comm.rank(), n = static_cast<int>(slabs.size());
    const SampleOptions& so = o.sampling;
    // Each rank sends the first layer of its slab to the rank before it.
    const auto exchange = [&](const std::vector<uint8_t>& first) {
        checkpoint(comm, "");
        std::vector<Bytes> out(static_cast<size_t>(comm.size()));
        if (me > 0 && me < n) out[static_cast<size_t>(me - 1)] = first;
        std::vector<Bytes> got = comm.allToAll(out);
        return me + 1 < n ? got[static_cast<size_t>(me + 1)] : std::vector<uint8_t>();
    };
    Part p;
    try {
        if (me < n) {
            injectedFailure(comm, false);
            p.slab = bakeExactSlabSections(mesh, shape, so.blockSize, so.bandVoxels, o.sign,
                                           slabs[me], exchange, so.threads, &stats);
        } else {
            exchange({});
        }
    } catch (const RankFailure&) {
        throw;
    } catch (...) {
        // Before the exchange the others wait at its checkpoint; after it, at the next one.
        checkpoint(comm, describeException(std::current_exception()));
    }
    return p;
}

// What each rank tells the others after its slab: its sections' sizes, then these counts (in
// that order, a u64 each; seconds as the bits of a double).
enum Count : size_t {
    kSurface = kSections,
    kKept,
    kOwnPageBytes,
    kInside,
    kOutside,
    kQueries,
    kSigns,
    kFilmSums,
    kSlabSeconds,
    kCounts
};

std::vector<uint64_t> countsOf(const Part& p, const ExactBakeStats& stats) {
    std::vector<uint64_t> mine(p.bytes, p.bytes + kSections);
    double seconds = 0;
    for (const BakeStage& st : stats.phases) seconds += st.seconds;
    mine.insert(mine.end(), {p.slab.surfaceBlocks, p.slab.kept.size(), p.ownPages.size(), p.inside,
                             p.outside, stats.distanceQueries, stats.signEvaluations,
                             stats.filmSums, std::bit_cast<uint64_t>(seconds)});
    return mine;
}

// The header and chunk table rank 0 writes, from every rank's counts and chunk sizes (pairs of
// global chunk number and compressed size), and where each chunk goes in the file.
struct Table {
    SdfgHeader h;
    SdfgCompressedHeader ch{};
    uint64_t ownPages = 0;
    std::vector<uint64_t> sizes, at;
    uint64_t dataStart = 0;
};

Table tableOf(const Layout& L, const std::vector<std::vector<uint64_t>>& counts,
              const std::vector<std::vector<uint64_t>>& chunkSizes, const GridShape& shape,
              const SampleOptions& so) {
    Table t;
    t.sizes.assign(L.firstChunk[kSections], 0);
    for (const std::vector<uint64_t>& r : chunkSizes)
        for (size_t i = 0; i + 1 < r.size(); i += 2) t.sizes.at(r[i]) = r[i + 1];
    uint64_t surface = 0;
    for (const std::vector<uint64_t>& r : counts) {
        surface += r[kSurface];
        t.ch.apronCount += r[kKept];
        t.ownPages += r[kOwnPageBytes] / kPageEntries;
    }
    const uint64_t V = static_cast<uint64_t>(so.blockSize) + 1;
    t.h =
        sdfgHeader(shape, GridKind::Sparse, so.blockSize, (so.bandVoxels - 1) * shape.voxelSize, 4);
    t.ch.chunkBytes = kSdfgChunkBytes;
    t.ch.sampleCount = surface * V * V * V;
    t.ch.chunkCount = t.sizes.size();
    t.dataStart = sizeof t.h + sizeof t.ch + sizeof t.ownPages + t.sizes.size() * sizeof(uint64_t);
    uint64_t payload = t.dataStart - sizeof t.h;
    t.at.resize(t.sizes.size());
    for (size_t i = 0; i < t.sizes.size(); ++i) {
        t.at[i] = sizeof t.h + payload;
        payload += t.sizes[i];
    }
    t.h.payloadBytes = payload;
    t.h.checksum = fnv1a64(t.sizes.data(), t.sizes.size() * sizeof(uint64_t),
                           fnv1a64(&t.ownPages, sizeof t.ownPages, fnv1a64(&t.ch, sizeof t.ch)));
    return t;
}

// Rank 0 makes the file under a temporary name (the header's room zeroed); every rank writes its
// chunks into it with MPI-IO; rank 0 then writes the header and chunk table and renames the file
// into place. Every rank has the temporary file removed if it is stopped meanwhile.
void writeFile(Communicator& comm, const std::string& path, const Table& t,
               const std::vector<OwnChunk>& chunks) {
    std::string error;
    std::unique_ptr<AtomicOutput> out;
    Bytes temp;
    try {
        if (comm.root()) {
            out = std::make_unique<AtomicOutput>(path);
            std::vector<char> head(t.dataStart, 0);
            out->write(head.data(), head.size());
            out->writeAt(0, head.data(), head.size());  // flushed: the file exists, sized
            temp.assign(out->tempPath().begin(), out->tempPath().end());
        }
    } catch (...) {
        error = describeException(std::current_exception());
    }
    checkpoint(comm, error);
    comm.broadcast(temp);
    const std::string tempPath(temp.begin(), temp.end());
    std::unique_ptr<SharedTemporary> shared;
    if (!comm.root()) shared = std::make_unique<SharedTemporary>(tempPath);
    injectedFailure(comm, true);
    SharedFile file;
    checkpoint(comm, file.open(comm, tempPath));
    for (const OwnChunk& c : chunks) {
        error = file.writeAt(t.at[c.number], c.packed.data(), c.packed.size());
        if (!error.empty()) {
            error = path + ": " + error;
            break;
        }
    }
    const std::string closed = file.close();
    if (error.empty() && !closed.empty()) error = path + ": " + closed;
    checkpoint(comm, error);
    try {
        if (comm.root()) {
            out->writeAt(0, &t.h, sizeof t.h);
            out->writeAt(sizeof t.h, &t.ch, sizeof t.ch);
            out->writeAt(sizeof t.h + sizeof t.ch, &t.ownPages, sizeof t.ownPages);
            out->writeAt(sizeof t.h + sizeof t.ch + sizeof t.ownPages, t.sizes.data(),
                         t.sizes.size() * sizeof(uint64_t));
            out->commit();
        }
    } catch (...) {
        error = describeException(std::current_exception());
    }
    checkpoint(comm, error);
    if (shared) shared->release();  // rank 0 renamed it into place
}

// Rank 0's report from every rank's counts and peaks: the job's counters, rank 0's phases, the
// slowest slab.
DistributedBakeSummary summaryOf(const std::vector<std::vector<uint64_t>>& counts,
                                 const std::vector<std::vector<uint64_t>>& peaks,
                                 const ExactBakeStats& rank0, const MeshBakeOptions& o,
                                 const GridShape& shape) {
    DistributedBakeSummary sum;
    sum.shape = shape;
    ExactBakeStats total;
    double slowest = 0;
    for (const std::vector<uint64_t>& r : counts) {
        sum.surface += r[kSurface];
        sum.inside += r[kInside];
        sum.outside += r[kOutside];
        total.distanceQueries += r[kQueries];
        total.signEvaluations += r[kSigns];
        total.filmSums += r[kFilmSums];
        slowest = std::max(slowest, std::bit_cast<double>(r[kSlabSeconds]));
    }
    for (const std::vector<uint64_t>& r : peaks)
        sum.peakMiB = std::max(sum.peakMiB, std::bit_cast<double>(r[0]));
    total.surfaceBlocks = sum.surface;
    for (const BakeStage& b : rank0.phases) sum.stages.push_back({"rank 0 " + b.name, b.seconds});
    char name[64];
    std::snprintf(name, sizeof name, "slabs (slowest rank %.3f s)", slowest);
    sum.stages.push_back({name, 0});  // the phase's seconds: the caller's
    sum.details = exactBakeDetails(total, o, shape);
    return sum;
}

}  // namespace

DistributedBakeSummary bakeExactToSdfg(Communicator& comm, const TriangleMesh& mesh,
                                       const MeshBakeOptions& o, const std::string& path,
                                       int level) {
    const auto start = Clock::now();
    const SampleOptions& so = o.sampling;
    const GridShape shape = o.shape ? *o.shape : gridShapeFor(mesh.bounds(), so);
    const int B = so.blockSize, me = comm.rank();
    int nb[3];
    for (int a = 0; a < 3; ++a) nb[a] = (shape.cells[a] + B - 1) / B;
    const std::vector<BlockSlab> slabs = tileSlabs(mesh, shape, B, so.bandVoxels, comm.size());
    ExactBakeStats stats;
    Part p = bakePart(comm, mesh, o, shape, slabs, stats);
    std::string error;
    try {
        blockTableOf(p, nb);
        sectionsOf(p);
    } catch (...) {
        error = describeException(std::current_exception());
    }
    checkpoint(comm, error);
    const double bakeSeconds = since(start);
    const auto writeStart = Clock::now();

    // Every rank's sizes and counts, then the chunks that start in this rank's parts compressed.
    const std::vector<std::vector<uint64_t>> counts = comm.allGather(countsOf(p, stats));
    const Layout L = layoutOf(counts);
    std::vector<OwnChunk> chunks;
    try {
        chunks = ownChunks(L, p, me, comm.allToAll(headsOut(L, p, me)));
        compressChunks(chunks, level, so.threads, path);
    } catch (...) {
        error = describeException(std::current_exception());
    }
    p = Part();  // compressed now
    checkpoint(comm, error);
    std::vector<uint64_t> sizes;  // (chunk number, compressed size) pairs
    for (const OwnChunk& c : chunks) sizes.insert(sizes.end(), {c.number, c.packed.size()});
    const Table t = tableOf(L, counts, comm.allGather(sizes), shape, so);
    writeFile(comm, path, t, chunks);
    const std::vector<std::vector<uint64_t>> peaks =
        comm.allGather({std::bit_cast<uint64_t>(peakResidentMiB())});

    DistributedBakeSummary sum = summaryOf(counts, peaks, stats, o, shape);
    sum.fileBytes = sizeof t.h + t.h.payloadBytes;
    sum.stages.back().seconds = bakeSeconds;
    sum.stages.push_back({"write", since(writeStart)});
    sum.details += ", " + std::to_string(comm.size()) + " ranks, " + std::to_string(slabs.size()) +
                   " slabs, written by every rank";
    return sum;
}

}  // namespace sdft
