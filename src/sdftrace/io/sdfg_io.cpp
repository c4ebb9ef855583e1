#include "sdftrace/io/sdfg_io.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>

#include "block_aprons.h"
#include "sdfg_layout.h"
#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/exec/all_finite.h"
#include "sdftrace/io/atomic_file.h"
#include "sdftrace/io/mapped_file.h"

namespace sdft {

namespace {

constexpr int kMaxCells = 32768;

}  // namespace

uint64_t fnv1a64(const void* data, size_t bytes, uint64_t h) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) {
        h ^= p[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

namespace {

using Header = SdfgHeader;
using CompressedHeader = SdfgCompressedHeader;
using TableHeader = SdfgTableHeader;
constexpr const char* kMagic = kSdfgMagic;
constexpr uint32_t kChunkBytes = kSdfgChunkBytes;

}  // namespace

SdfgHeader sdfgHeader(const GridShape& s, GridKind kind, int blockSize, float background,
                      uint32_t version) {
    SdfgHeader h{};
    h.version = version;
    std::memcpy(h.magic, kSdfgMagic, 4);
    h.kind = static_cast<uint32_t>(kind);
    for (int a = 0; a < 3; ++a) {
        h.cells[a] = s.cells[a];
        h.origin[a] = s.origin[a];
    }
    h.voxelSize = s.voxelSize;
    h.blockSize = kind == GridKind::Sparse ? static_cast<uint32_t>(blockSize) : 0;
    h.background = background;
    return h;
}

namespace {

// The header's fields that describe the grid (payload size and checksum left to the writer).
Header headerOf(const Grid& grid, uint32_t version) {
    return sdfgHeader(grid.shape(), grid.kind(),
                      grid.kind() == GridKind::Sparse ? grid.blockSize() : 0, grid.background(),
                      version);
}

void saveRaw(const Grid& grid, const std::string& path) {
    const bool tex = !grid.texcoords().empty();
    Header h = headerOf(grid, tex ? 2 : 1);
    uint64_t sum = 0xcbf29ce484222325ull;
    const std::vector<uint8_t> flags =
        grid.kind() == GridKind::Sparse ? grid.denseFlags() : std::vector<uint8_t>();
    // Versions 1 and 2 store each surface block's (B+1)^3 vertices.
    const std::vector<float> blockSamples = grid.expandedBlockSamples();  // empty when dense
    const std::vector<float> texcoords = grid.expandedTexcoords();
    if (grid.kind() == GridKind::Dense) {
        h.payloadBytes = grid.samples().size() * sizeof(float);
        sum = fnv1a64(grid.samples().data(), h.payloadBytes, sum);
    } else {
        h.payloadBytes = flags.size() + blockSamples.size() * sizeof(float);
        sum = fnv1a64(flags.data(), flags.size(), sum);
        sum = fnv1a64(blockSamples.data(), blockSamples.size() * sizeof(float), sum);
    }
    const uint32_t texHeader[2] = {static_cast<uint32_t>(grid.texcoordKind()), 0};
    if (tex) {
        h.payloadBytes += sizeof texHeader + texcoords.size() * sizeof(float);
        sum = fnv1a64(texHeader, sizeof texHeader, sum);
        sum = fnv1a64(texcoords.data(), texcoords.size() * sizeof(float), sum);
    }
    h.checksum = sum;

    AtomicOutput out(path);
    out.write(&h, sizeof h);
    if (grid.kind() == GridKind::Dense) {
        out.write(grid.samples().data(), grid.samples().size() * sizeof(float));
    } else {
        out.write(flags.data(), flags.size());
        out.write(blockSamples.data(), blockSamples.size() * sizeof(float));
    }
    if (tex) {
        out.write(texHeader, sizeof texHeader);
        out.write(texcoords.data(), texcoords.size() * sizeof(float));
    }
    out.commit();
}

// ---- versions 3 to 5: compressed sections ----

size_t tableHeaderBytes(uint32_t version) { return version >= 5 ? 24 : version == 4 ? 8 : 0; }

// The sections of the uncompressed payload, in file order. Dense: samples. Sparse: the block
// flags (version 3: one byte per block of the box; versions 4 and 5: one byte per tile, 0
// outside, 1 inside, 2 own page, then the own pages' 512 flags each in tile order); then, up to
// version 4, the surface blocks' own samples, their apron masks, the explicit apron samples
// (block_aprons.h), and in version 5 the grid's own buffers (storedSections). Then texture
// coordinates, if any. Floats (and version 5's other 4-byte words) are byte-shuffled before
// compression (the four bytes of each word in four planes: sign and exponent bytes repeat, and
// compress far better).
struct Section {
    const char* data;
    uint64_t bytes;
    bool floats;
};

template <class T>
Section section(const std::vector<T>& v, bool floats) {
    return {reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T), floats};
}

// One chunk: section `section`, bytes [offset, offset + bytes).
struct Chunk {
    int section;
    uint64_t offset, bytes;
};

std::vector<Chunk> chunksOf(const std::vector<uint64_t>& sectionBytes, uint32_t chunkBytes) {
    std::vector<Chunk> out;
    for (size_t s = 0; s < sectionBytes.size(); ++s)
        for (uint64_t o = 0; o < sectionBytes[s]; o += chunkBytes)
            out.push_back(
                {static_cast<int>(s), o, std::min<uint64_t>(chunkBytes, sectionBytes[s] - o)});
    return out;
}

void shuffleFloats(const char* in, char* out, uint64_t bytes) {
    const uint64_t n = bytes / 4;
    for (uint64_t i = 0; i < n; ++i)
        for (int b = 0; b < 4; ++b) out[b * n + i] = in[4 * i + b];
}

void unshuffleFloats(const char* in, char* out, uint64_t bytes) {
    const uint64_t n = bytes / 4;
    for (uint64_t i = 0; i < n; ++i)
        for (int b = 0; b < 4; ++b) out[4 * i + b] = in[b * n + i];
}

}  // namespace

std::vector<char> compressSdfgChunk(const char* src, uint64_t bytes, bool floats, int level,
                                    std::vector<char>& scratch, const std::string& path) {
    if (floats) {
        if (scratch.size() < bytes) scratch.resize(bytes);
        shuffleFloats(src, scratch.data(), bytes);
        src = scratch.data();
    }
    ZSTD_CCtx* ctx = ZSTD_createCCtx();
    ZSTD_CCtx_setParameter(ctx, ZSTD_c_compressionLevel, level);
    ZSTD_CCtx_setParameter(ctx, ZSTD_c_checksumFlag, 1);
    std::vector<char> out(ZSTD_compressBound(bytes));
    const size_t n = ZSTD_compress2(ctx, out.data(), out.size(), src, bytes);
    ZSTD_freeCCtx(ctx);
    if (ZSTD_isError(n))
        throw InputError(path + ": compression failed (" + ZSTD_getErrorName(n) + ")");
    out.resize(n);
    out.shrink_to_fit();
    return out;
}

namespace {

// One chunk, its floats byte-shuffled, compressed by zstd with its checksum.
std::vector<char> compressChunk(const std::vector<Section>& sections, const Chunk& ch, int level,
                                std::vector<char>& scratch, const std::string& path) {
    const Section& sec = sections[static_cast<size_t>(ch.section)];
    return compressSdfgChunk(sec.data + ch.offset, ch.bytes, sec.floats, level, scratch, path);
}

// Chunks compressed on every core and written in order as they come: the file is written while
// the rest compresses, and only a few chunks are held at once. Fills in each chunk's compressed
// size; returns their sum.
uint64_t writeChunks(AtomicOutput& out, const std::vector<Section>& sections,
                     const std::vector<Chunk>& chunks, int level, std::vector<uint64_t>& table,
                     const std::string& path) {
    using Packed = std::pair<size_t, std::vector<char>>;  // chunk, compressed bytes
    tbb::enumerable_thread_specific<std::vector<char>> shuffled;
    size_t next = 0;
    uint64_t written = 0;
    tbb::parallel_pipeline(
        2 * static_cast<size_t>(tbb::this_task_arena::max_concurrency()),
        tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order,
                                       [&](tbb::flow_control& fc) -> size_t {
                                           if (next == chunks.size()) fc.stop();
                                           return next++;
                                       }) &
            tbb::make_filter<size_t, Packed>(
                tbb::filter_mode::parallel,
                [&](size_t c) -> Packed {
                    return {c, compressChunk(sections, chunks[c], level, shuffled.local(), path)};
                }) &
            tbb::make_filter<Packed, void>(tbb::filter_mode::serial_in_order, [&](const Packed& p) {
                table[p.first] = p.second.size();
                written += p.second.size();
                out.write(p.second.data(), p.second.size());
            }));
    return written;
}

// Versions 4 and 5: a sparse grid's block table by tiles, its kinds (filled into `tileKinds`)
// and its own pages' flags (from the grid's), and their count in `th`.
void tableSections(const Grid& grid, std::vector<uint8_t>& tileKinds, TableHeader& th,
                   std::vector<Section>& sections) {
    tileKinds.resize(grid.tilePage().size());
    for (size_t t = 0; t < tileKinds.size(); ++t)
        tileKinds[t] = static_cast<uint8_t>(std::min(grid.tilePage()[t], kFirstOwnPage));
    const std::vector<uint8_t>& slots = grid.flags();
    th.ownPages = slots.size() / kPageEntries - kFirstOwnPage;
    sections = {section(tileKinds, false),
                {reinterpret_cast<const char*>(slots.data()) + kFirstOwnPage * kPageEntries,
                 th.ownPages * kPageEntries, false}};
}

// Version 5's sections of a sparse grid: its block table by tiles (as version 4), then its sample
// blocks, neighbour entries, apron blocks' owners and codes, cell masks, per-slot skip distances
// and Lipschitz codes, per-tile skip distances and Lipschitz codes: the grid as it is in memory,
// written from its own buffers (4-byte words shuffled as floats are).
void storedSections(const Grid& grid, std::vector<uint8_t>& tileKinds, TableHeader& th,
                    std::vector<Section>& sections) {
    tableSections(grid, tileKinds, th, sections);
    th.surfaceBlocks = grid.surfaceBlockCount();
    th.lipschitz = grid.lipschitz();
    th.gentleLipschitz = grid.gentleLipschitz();
    sections.insert(sections.end(),
                    {section(grid.blockSamples(), true), section(grid.blockNeighbors(), true),
                     section(grid.apronFrom(), true), section(grid.apronCode(), false),
                     section(grid.cellMasks(), true), section(grid.blockSkip(), false),
                     section(grid.blockLipschitz(), false), section(grid.tileSkip(), false),
                     section(grid.tileLipschitz(), false)});
}

void saveCompressed(const Grid& grid, const std::string& path, int level, uint32_t version) {
    std::vector<Section> sections;
    ApronSamples aprons;
    std::vector<uint8_t> flags, tileKinds;
    TableHeader th{};
    if (grid.kind() == GridKind::Dense) {
        sections.push_back(section(grid.samples(), true));
    } else if (version >= 5) {
        storedSections(grid, tileKinds, th, sections);
    } else {
        aprons = splitAprons(grid);
        if (version == 3) {
            flags = grid.denseFlags();
            sections = {section(flags, false)};
        } else {
            tableSections(grid, tileKinds, th, sections);
        }
        // The own samples straight from the grid's buffer (its first B^3 per surface block).
        const uint64_t B = static_cast<uint64_t>(grid.blockSize());
        sections.insert(sections.end(),
                        {{reinterpret_cast<const char*>(grid.blockSamples().data()),
                          grid.surfaceBlockCount() * B * B * B * sizeof(float), true},
                         section(aprons.masks, false),
                         section(aprons.explicitly, true)});
    }
    // Texture coordinates: per stored sample in version 5, as the grid keeps them; before, per
    // (B+1)^3 vertex.
    std::vector<float> expandedTexcoords;
    if (!grid.texcoords().empty()) {
        if (version < 5) expandedTexcoords = grid.expandedTexcoords();
        sections.push_back(section(version < 5 ? expandedTexcoords : grid.texcoords(), true));
    }
    std::vector<uint64_t> sectionBytes;
    for (const Section& s : sections) sectionBytes.push_back(s.bytes);
    const std::vector<Chunk> chunks = chunksOf(sectionBytes, kChunkBytes);

    Header h = headerOf(grid, version);
    CompressedHeader ch{};
    ch.texKind = grid.texcoords().empty() ? 0 : static_cast<uint32_t>(grid.texcoordKind());
    ch.chunkBytes = kChunkBytes;
    const uint64_t B = static_cast<uint64_t>(grid.blockSize());
    ch.sampleCount = grid.kind() == GridKind::Dense ? grid.storedSamples()
                     : version >= 5                 ? grid.blockSamples().size()
                                    : grid.surfaceBlockCount() * (B + 1) * (B + 1) * (B + 1);
    // Version 5: the sample blocks past the surface ones; before, the kept apron samples.
    ch.apronCount = version >= 5 ? grid.apronFrom().size() : aprons.explicitly.size();
    ch.chunkCount = chunks.size();
    const size_t thBytes = tableHeaderBytes(version);
    std::vector<uint64_t> table(chunks.size(), 0);  // compressed sizes, known once written
    AtomicOutput out(path);
    out.write(&h, sizeof h);
    out.write(&ch, sizeof ch);
    out.write(&th, thBytes);
    out.write(table.data(), table.size() * sizeof(uint64_t));
    h.payloadBytes = sizeof ch + thBytes + table.size() * sizeof(uint64_t) +
                     writeChunks(out, sections, chunks, level, table, path);
    h.checksum = fnv1a64(table.data(), table.size() * sizeof(uint64_t),
                         fnv1a64(&th, thBytes, fnv1a64(&ch, sizeof ch)));
    out.writeAt(0, &h, sizeof h);
    out.writeAt(sizeof h + sizeof ch + thBytes, table.data(), table.size() * sizeof(uint64_t));
    out.commit();
}
}  // namespace

void saveSdfg(const Grid& grid, const std::string& path, const SdfgWriteOptions& options) {
    SDFT_CHECK(options.version >= 3 && options.version <= 5);
    // Versions 1-3 store one flag per block of the bounding box (the grid keeps them paged, see
    // block_table.h): checked before that array is made.
    const bool flatFlags = !options.compress || options.version == 3;
    if (grid.kind() == GridKind::Sparse && flatFlags) {
        const GridView v = grid.view();
        checkMemoryBudget(static_cast<double>(v.blocks[0]) * v.blocks[1] * v.blocks[2], path,
                          "the flat block flags of .sdfg versions 1-3",
                          "save it compressed (version 4 stores the block table by tiles)");
    }
    // Version 5 stores a sparse grid as it is in memory; dense and complete grids (nothing to
    // store beyond their samples, or a layout of their own) stay version 4.
    const uint32_t version =
        options.version == 5 && (grid.kind() == GridKind::Dense || grid.isComplete())
            ? 4
            : options.version;
    if (options.compress)
        saveCompressed(grid, path, options.level, version);
    else
        saveRaw(grid, path);
}

namespace {

// What the header says the payload holds, checked against the file's size.
struct PayloadLayout {
    GridKind kind = GridKind::Dense;
    bool texcoords = false;  // version 2: u32 kind, u32 reserved, 3 floats per sample
    uint64_t bytes = 0;      // the payload after the header
    uint64_t numBlocks = 0;  // sparse: one flag byte each
    uint64_t texHeaderBytes = 0, floatsPerSample = 1;
};

Header readHeader(const MappedFile& file, const std::string& path) {
    Header h{};
    if (file.size() < sizeof h)
        throw InputError(path + ": truncated: shorter than the 64-byte .sdfg header");
    std::memcpy(&h, file.data(), sizeof h);
    if (std::memcmp(h.magic, kMagic, 4) != 0)
        throw InputError(path + ": not an .sdfg file (bad magic)");
    if (h.version < 1 || h.version > kSdfgVersion) {
        throw InputError(path + ": .sdfg version " + std::to_string(h.version) +
                         " is not supported (this build reads versions 1 to " +
                         std::to_string(kSdfgVersion) + ")");
    }
    if (h.kind > 1)
        throw InputError(path + ": unknown grid kind " + std::to_string(h.kind) +
                         " (accepted: 0 dense, 1 sparse)");
    return h;
}

GridShape shapeOf(const Header& h, const std::string& path) {
    GridShape s;
    for (int a = 0; a < 3; ++a) {
        if (h.cells[a] < 1 || h.cells[a] > kMaxCells) {
            throw InputError(path + ": grid size " + std::to_string(h.cells[0]) + "x" +
                             std::to_string(h.cells[1]) + "x" + std::to_string(h.cells[2]) +
                             " is out of range (1 to " + std::to_string(kMaxCells) +
                             " cells per axis)");
        }
        if (!std::isfinite(h.origin[a])) throw InputError(path + ": non-finite origin");
        s.cells[a] = h.cells[a];
        s.origin[a] = h.origin[a];
    }
    if (!(h.voxelSize > 0) || !std::isfinite(h.voxelSize))
        throw InputError(path + ": voxel size must be positive and finite");
    s.voxelSize = h.voxelSize;
    return s;
}

// Blocks of B cells per axis, and tiles of 8^3 of them, over a grid of shape s.
void blocksOf(const GridShape& s, int B, int blocks[3]) {
    for (int a = 0; a < 3; ++a) blocks[a] = (s.cells[a] + B - 1) / B;
}
uint64_t tileCount(const GridShape& s, int B) {
    int blocks[3];
    blocksOf(s, B, blocks);
    uint64_t tiles = 1;
    for (int a = 0; a < 3; ++a) tiles *= (blocks[a] + kTileBlocks - 1) / kTileBlocks;
    return tiles;
}

// A sparse header's block size and background, checked; the number of blocks they give.
uint64_t sparseBlockCount(const Header& h, const GridShape& s, const std::string& path) {
    if (h.blockSize != 4 && h.blockSize != 8)
        throw InputError(path + ": block size " + std::to_string(h.blockSize) +
                         " (accepted: 4, 8)");
    if (!(h.background > 0) || !std::isfinite(h.background))
        throw InputError(path + ": background must be positive and finite");
    int blocks[3];
    blocksOf(s, static_cast<int>(h.blockSize), blocks);
    return static_cast<uint64_t>(blocks[0]) * blocks[1] * blocks[2];
}

// The payload expected from the header alone, checked against the file before allocating.
PayloadLayout layoutOf(const Header& h, const GridShape& s, const std::string& path,
                       uint64_t fileBytes) {
    PayloadLayout l;
    l.kind = static_cast<GridKind>(h.kind);
    l.texcoords = h.version == 2;
    l.texHeaderBytes = l.texcoords ? 8 : 0;
    l.floatsPerSample = l.texcoords ? 4 : 1;
    if (l.kind == GridKind::Dense) {
        l.bytes = static_cast<uint64_t>(s.vertexCount()) * sizeof(float) * l.floatsPerSample +
                  l.texHeaderBytes;
    } else {
        l.numBlocks = sparseBlockCount(h, s, path);
        const uint64_t perBlockBytes = static_cast<uint64_t>(h.blockSize + 1) * (h.blockSize + 1) *
                                       (h.blockSize + 1) * sizeof(float) * l.floatsPerSample;
        const uint64_t fixed = l.numBlocks + l.texHeaderBytes;
        if (h.payloadBytes < fixed || (h.payloadBytes - fixed) % perBlockBytes != 0 ||
            (h.payloadBytes - fixed) / perBlockBytes > l.numBlocks) {
            throw InputError(path + ": corrupt header: payload size does not fit the block layout");
        }
        l.bytes = h.payloadBytes;
    }
    if (h.payloadBytes != l.bytes)
        throw InputError(path + ": corrupt header: payload size does not match the grid size");
    if (fileBytes - sizeof h < l.bytes) {
        throw InputError(path + ": truncated: the header promises " + std::to_string(l.bytes) +
                         " payload bytes, the file has " + std::to_string(fileBytes - sizeof h));
    }
    if (fileBytes - sizeof h > l.bytes)
        throw InputError(path + ": corrupt: trailing bytes after the payload");
    return l;
}

}  // namespace

namespace {

using CorruptError = std::function<InputError(const std::string&)>;

// The sizes of a version-5 sparse file's sections (storedSections), from its headers.
std::vector<uint64_t> storedSectionBytes(const Header& h, const GridShape& s,
                                         const CompressedHeader& ch, const TableHeader& th,
                                         const std::string& path, const CorruptError& corrupt) {
    const uint64_t numBlocks = sparseBlockCount(h, s, path);
    const uint64_t B = h.blockSize, own = B * B * B, words = (own + 63) / 64;
    const uint64_t tiles = tileCount(s, static_cast<int>(B));
    if (th.ownPages > tiles) throw corrupt("own page count");
    const uint64_t surface = th.surfaceBlocks, extra = ch.apronCount;
    if (surface > th.ownPages * kPageEntries || surface > numBlocks)
        throw corrupt("surface block count does not fit the block table");
    if (extra > 7 * surface || ch.sampleCount != (surface + extra) * own)
        throw corrupt("sample count does not fit the block layout");
    const uint64_t slots = (th.ownPages + kFirstOwnPage) * kPageEntries;
    return {tiles,
            th.ownPages * kPageEntries,
            ch.sampleCount * sizeof(float),
            surface * 8 * sizeof(int32_t),
            extra * sizeof(int32_t),
            extra,
            surface * words * sizeof(uint64_t),
            slots,
            slots,
            tiles,
            tiles};
}

// A version-3 to -5 file's section sizes (in file order), from its headers; every count checked
// against the grid before anything is allocated from it.
std::vector<uint64_t> compressedSections(const Header& h, const GridShape& s,
                                         const CompressedHeader& ch, const TableHeader& th,
                                         const std::string& path, const CorruptError& corrupt) {
    if (ch.chunkBytes < 4096 || ch.chunkBytes > (1u << 28) || ch.chunkBytes % 4 != 0)
        throw corrupt("chunk size " + std::to_string(ch.chunkBytes));
    if (ch.texKind > static_cast<uint32_t>(TexcoordKind::Cylinder))
        throw corrupt("unknown texture-coordinate kind " + std::to_string(ch.texKind));
    std::vector<uint64_t> sections;
    if (static_cast<GridKind>(h.kind) == GridKind::Dense) {
        if (ch.sampleCount != s.vertexCount()) throw corrupt("sample count");
        if (ch.apronCount != 0) throw corrupt("apron sample count");
        if (th.ownPages != 0) throw corrupt("own page count");
        sections = {ch.sampleCount * sizeof(float)};
    } else if (h.version >= 5) {
        sections = storedSectionBytes(h, s, ch, th, path, corrupt);
    } else {
        const uint64_t numBlocks = sparseBlockCount(h, s, path);
        const int B = static_cast<int>(h.blockSize);
        const uint64_t perBlock = static_cast<uint64_t>(B + 1) * (B + 1) * (B + 1);
        if (ch.sampleCount % perBlock != 0 || ch.sampleCount / perBlock > numBlocks)
            throw corrupt("sample count does not fit the block layout");
        const uint64_t surface = ch.sampleCount / perBlock;
        if (ch.apronCount > surface * apronSize(B)) throw corrupt("apron sample count");
        if (h.version >= 4) {
            const uint64_t tiles = tileCount(s, B);
            if (th.ownPages > tiles) throw corrupt("own page count");
            if (surface > th.ownPages * kPageEntries)
                throw corrupt("sample count does not fit the block table");
            sections = {tiles, th.ownPages * kPageEntries};
        } else {
            sections = {numBlocks};
        }
        sections.insert(sections.end(), {surface * B * B * B * sizeof(float),
                                         surface * apronWords(B) * sizeof(uint64_t),
                                         ch.apronCount * sizeof(float)});
    }
    if (ch.texKind) sections.push_back(3 * ch.sampleCount * sizeof(float));
    return sections;
}

// Where each chunk starts in the file: the chunk table read, checked against the header's checksum
// and the file's size.
std::vector<uint64_t> chunkStarts(const MappedFile& file, const Header& h,
                                  const CompressedHeader& ch, const TableHeader& th, size_t thBytes,
                                  std::vector<uint64_t>& table, const CorruptError& corrupt) {
    const uint64_t fileBytes = file.size();
    table.resize(ch.chunkCount);
    const uint64_t tableAt = sizeof h + sizeof ch + thBytes;
    std::memcpy(table.data(), file.data() + tableAt, table.size() * sizeof(uint64_t));
    if (fnv1a64(table.data(), table.size() * sizeof(uint64_t),
                fnv1a64(&th, thBytes, fnv1a64(&ch, sizeof ch))) != h.checksum)
        throw corrupt("table checksum mismatch");
    std::vector<uint64_t> start(table.size());
    uint64_t at = tableAt + table.size() * sizeof(uint64_t);
    for (size_t c = 0; c < table.size(); ++c) {
        if (table[c] > fileBytes - at)
            throw corrupt("chunk " + std::to_string(c) + " past the end");
        start[c] = at;
        at += table[c];
    }
    if (at != fileBytes) throw corrupt("trailing bytes after the chunks");
    return start;
}

// Chunks [first, last) decompressed in parallel to their section's `dest[section]`, at their
// offset in the section less `shift` (floats unshuffled; sections whose destination is null
// skipped), each checked against its size and zstd's checksum and then released from memory.
struct ChunkRange {
    size_t first, last;
    uint64_t shift = 0;
};
void decompressChunks(const MappedFile& file, const std::vector<Chunk>& chunks,
                      const std::vector<uint64_t>& start, const std::vector<uint64_t>& table,
                      const std::vector<char*>& dest, const std::vector<bool>& floats,
                      const CorruptError& corrupt, ChunkRange range) {
    // One shuffle buffer per thread, kept across its chunks (a fresh 4 MiB each time costs a
    // thousand page faults).
    tbb::enumerable_thread_specific<std::vector<char>> buffers;
    tbb::parallel_for(range.first, range.last, [&](size_t c) {
        const Chunk& k = chunks[c];
        if (!dest[k.section]) return;  // a section read in another pass
        char* out = dest[k.section] + (k.offset - range.shift);
        std::vector<char>& shuffled = buffers.local();
        if (floats[k.section] && shuffled.size() < k.bytes) shuffled.resize(k.bytes);
        char* target = floats[k.section] ? shuffled.data() : out;
        const size_t got = ZSTD_decompress(target, k.bytes, file.data() + start[c], table[c]);
        if (ZSTD_isError(got) || got != k.bytes)
            throw corrupt("chunk " + std::to_string(c) + " (" +
                          (ZSTD_isError(got) ? ZSTD_getErrorName(got) : "wrong size") + ")");
        if (floats[k.section]) unshuffleFloats(shuffled.data(), out, k.bytes);
        file.release(start[c], table[c]);  // read once: the file need not stay in our memory
    });
}

// A version-4 or -5 file's block table: per tile 0 (outside), 1 (inside) or 2 (its own page, the
// pages in tile order), and the own pages' flags.
BlockTable tableOf(const int blocks[3], const std::vector<uint8_t>& tileKinds,
                   std::vector<uint8_t> ownFlags, const CorruptError& corrupt) {
    BlockTable t = BlockTable::empty(blocks);
    if (tileKinds.size() != t.tilePage.size()) throw corrupt("tile count");
    int32_t next = kFirstOwnPage;
    for (size_t tile = 0; tile < tileKinds.size(); ++tile) {
        if (tileKinds[tile] > kFirstOwnPage)
            throw corrupt("tile " + std::to_string(tile) + " has kind " +
                          std::to_string(tileKinds[tile]) +
                          " (accepted: 0 outside, 1 inside, 2 own page)");
        t.tilePage[tile] = tileKinds[tile] < kFirstOwnPage ? tileKinds[tile] : next++;
    }
    if (static_cast<size_t>(next - kFirstOwnPage) * kPageEntries != ownFlags.size())
        throw corrupt("the tiles name " + std::to_string(next - kFirstOwnPage) +
                      " own pages; the flags do not");
    t.flags.insert(t.flags.end(), ownFlags.begin(), ownFlags.end());
    // Entries of blocks past the grid's last ones (tiles on its upper faces) mean nothing: outside.
    const std::vector<int> own = t.ownTiles();
    for (size_t p = 0; p * 3 < own.size(); ++p) {
        const int tile[3] = {own[3 * p], own[3 * p + 1], own[3 * p + 2]};
        if ((tile[0] + 1) * kTileBlocks <= blocks[0] && (tile[1] + 1) * kTileBlocks <= blocks[1] &&
            (tile[2] + 1) * kTileBlocks <= blocks[2])
            continue;
        uint8_t* page = t.flags.data() + (p + kFirstOwnPage) * kPageEntries;
        for (int l = 0; l < kPageEntries; ++l) {
            const int b[3] = {tile[0] * kTileBlocks + (l & (kTileBlocks - 1)),
                              tile[1] * kTileBlocks + ((l >> kTileShift) & (kTileBlocks - 1)),
                              tile[2] * kTileBlocks + (l >> (2 * kTileShift))};
            if (b[0] >= blocks[0] || b[1] >= blocks[1] || b[2] >= blocks[2])
                page[l] = static_cast<uint8_t>(BlockFlag::Outside);
        }
    }
    return t;
}

// A version-3 to -5 file's section and chunk tables, checked against the header and the file
// before anything is allocated from their numbers.
struct Compressed {
    CompressedHeader ch{};
    TableHeader th{};
    std::vector<uint64_t> sectionBytes;  // uncompressed, in file order
    uint64_t total = 0;                  // their sum
    std::vector<Chunk> chunks;
    std::vector<uint64_t> start, size;  // per chunk: where it starts in the file, its bytes there
    CorruptError corrupt;

    Compressed(const MappedFile& file, const Header& h, const GridShape& s, const std::string& path)
        : corrupt([path](const std::string& what) {
              return InputError(path + ": corrupt compressed .sdfg: " + what);
          }) {
        const uint64_t fileBytes = file.size();
        if (h.payloadBytes != fileBytes - sizeof h)
            throw corrupt("the header's payload size does not match the file size");
        const size_t thBytes = tableHeaderBytes(h.version);
        if (fileBytes - sizeof h < sizeof ch + thBytes) throw corrupt("truncated section header");
        std::memcpy(&ch, file.data() + sizeof h, sizeof ch);
        std::memcpy(&th, file.data() + sizeof h + sizeof ch, thBytes);
        sectionBytes = compressedSections(h, s, ch, th, path, corrupt);
        // The chunk count follows from the sections.
        uint64_t expectedChunks = 0;
        for (uint64_t b : sectionBytes) {
            total += b;
            expectedChunks += (b + ch.chunkBytes - 1) / ch.chunkBytes;
        }
        if (ch.chunkCount != expectedChunks) throw corrupt("chunk count");
        if (ch.chunkCount > (fileBytes - sizeof h - sizeof ch - thBytes) / sizeof(uint64_t))
            throw corrupt("truncated chunk table");
        chunks = chunksOf(sectionBytes, ch.chunkBytes);
        start = chunkStarts(file, h, ch, th, thBytes, size, corrupt);
    }

    // Where sections decompress (null: not in this pass), and which are byte-shuffled.
    struct Targets {
        std::vector<char*> dest;
        std::vector<bool> shuffled;
        const std::vector<uint64_t>& bytes;
        explicit Targets(const Compressed& c)
            : dest(c.sectionBytes.size(), nullptr),
              shuffled(c.sectionBytes.size(), false),
              bytes(c.sectionBytes) {}
        void at(size_t section, char* out, bool isShuffled) {
            dest[section] = out;
            shuffled[section] = isShuffled;
        }
        // `v` sized to the section, which decompresses into it.
        template <class T>
        void into(size_t section, std::vector<T>& v, bool isShuffled) {
            v.resize(bytes[section] / sizeof(T));
            at(section, reinterpret_cast<char*>(v.data()), isShuffled);
        }
    };

    // Decompresses the sections `t` names (unshuffling those it says), in parallel, and clears
    // them from `t`.
    void decompress(const MappedFile& file, Targets& t) const {
        decompressChunks(file, chunks, start, size, t.dest, t.shuffled, corrupt,
                         {0, chunks.size()});
        std::fill(t.dest.begin(), t.dest.end(), nullptr);
    }

    // Section `section`'s bytes [from, to), rounded out to whole chunks, decompressed into `out`
    // (resized); returns where `from` lies in it.
    size_t decompressPart(const MappedFile& file, size_t section, uint64_t from, uint64_t to,
                          bool isFloat, std::vector<char>& out) const {
        size_t first = 0;  // the section's first chunk
        while (first < chunks.size() && chunks[first].section != static_cast<int>(section)) ++first;
        const uint64_t c0 = from / ch.chunkBytes, c1 = (to + ch.chunkBytes - 1) / ch.chunkBytes;
        const uint64_t shift = c0 * ch.chunkBytes;
        out.resize(std::min(c1 * ch.chunkBytes, sectionBytes[section]) - shift);
        Targets t(*this);
        t.at(section, out.data(), isFloat);
        decompressChunks(file, chunks, start, size, t.dest, t.shuffled, corrupt,
                         {first + c0, first + c1, shift});
        return from - shift;
    }

    // A sparse grid's block table, from its first section(s) (versions 4 and 5: tile kinds and
    // own pages; version 3: flat flags).
    BlockTable blockTable(const MappedFile& file, const Header& h, const GridShape& s,
                          const std::string& path) const {
        Targets t(*this);
        std::vector<uint8_t> tileKinds, flags;
        if (h.version >= 4) t.into(0, tileKinds, false);
        t.into(tableSections(h) - 1, flags, false);
        decompress(file, t);
        int blocks[3];
        blocksOf(s, static_cast<int>(h.blockSize), blocks);
        return h.version >= 4 ? tableOf(blocks, tileKinds, std::move(flags), corrupt)
                              : BlockTable::fromDense(blocks, flags, path);
    }
    static size_t tableSections(const Header& h) { return h.version >= 4 ? 2 : 1; }
};

// A version-5 sparse file: its sections decompressed in parallel into the grid's own buffers,
// each index and code checked (SparseGridBuilder::fromStored); nothing recomputed.
Grid loadStored(const MappedFile& file, const Header& h, const GridShape& s, const Compressed& c,
                const std::string& path) {
    SparseGridBuilder builder(s, static_cast<int>(h.blockSize), h.background,
                              c.blockTable(file, h, s, path), path, /*allocate=*/false);
    if (builder.surfaceBlocks() != c.th.surfaceBlocks)
        throw c.corrupt("the flags name " + std::to_string(builder.surfaceBlocks()) +
                        " surface blocks; the header " + std::to_string(c.th.surfaceBlocks));
    StoredSparse p;
    std::vector<float> texcoords;
    Compressed::Targets t(c);
    size_t next = 2;  // after the block table's two sections, in storedSections' order
    auto into = [&](auto& v, bool shuffled) { t.into(next++, v, shuffled); };
    into(p.blockSamples, true);
    into(p.blockNeighbors, true);
    into(p.apronFrom, true);
    into(p.apronCode, false);
    into(p.cellMasks, true);
    into(p.blockSkip, false);
    into(p.blockLipschitz, false);
    into(p.tileSkip, false);
    into(p.tileLipschitz, false);
    if (c.ch.texKind) into(texcoords, true);
    c.decompress(file, t);
    p.lipschitz = c.th.lipschitz;
    p.gentleLipschitz = c.th.gentleLipschitz;
    Grid grid = builder.fromStored(std::move(p), path);
    if (c.ch.texKind)
        grid.setTexcoords(static_cast<TexcoordKind>(c.ch.texKind), std::move(texcoords), path);
    return grid;
}

// Decompresses a version-3 to -5 file's chunks in parallel straight into the grid's buffers.
Grid loadCompressed(const MappedFile& file, const Header& h, const GridShape& s,
                    const std::string& path) {
    const Compressed c(file, h, s, path);
    const CorruptError& corrupt = c.corrupt;
    const std::vector<uint64_t>& sectionBytes = c.sectionBytes;
    // The grid's samples are decompressed where the grid keeps them: beside them only the apron
    // masks and kept samples, and the tables.
    checkMemoryBudget(1.25 * static_cast<double>(c.total), path,
                      "the grid's samples and the structures built from them",
                      "convert or bake it at a lower resolution");
    if (static_cast<GridKind>(h.kind) == GridKind::Sparse && h.version >= 5)
        return loadStored(file, h, s, c, path);
    Compressed::Targets t(c);
    std::vector<float> texcoords;
    Grid grid;
    if (static_cast<GridKind>(h.kind) == GridKind::Dense) {
        std::vector<float> samples;
        t.into(0, samples, true);
        if (c.ch.texKind) t.into(1, texcoords, true);
        c.decompress(file, t);
        if (!allFinite(samples.data(), samples.size())) throw corrupt("non-finite sample");
        grid = Grid::dense(s, std::move(samples));
    } else {
        // First the block table, which numbers the surface blocks and sizes the grid's buffers.
        const int B = static_cast<int>(h.blockSize);
        SparseGridBuilder builder(s, B, h.background, c.blockTable(file, h, s, path), path);
        const size_t tableSections = Compressed::tableSections(h);
        const uint64_t ownBytes = builder.surfaceBlocks() * static_cast<uint64_t>(B * B * B) * 4;
        if (sectionBytes[tableSections] != ownBytes)
            throw corrupt("the flags name " + std::to_string(builder.surfaceBlocks()) +
                          " surface blocks; the samples do not");
        // Then the own samples straight into the grid's buffer, and the apron masks.
        std::vector<uint64_t> masks;
        t.at(tableSections, reinterpret_cast<char*>(builder.ownSamples()), true);
        t.into(tableSections + 1, masks, false);
        if (c.ch.texKind) t.into(tableSections + 3, texcoords, true);
        c.decompress(file, t);
        // The kept apron samples, a few chunks at a time as the blocks ask for them.
        const size_t keptSection = tableSections + 2;
        auto read = [&c, &file, keptSection, window = std::make_shared<std::vector<char>>()](
                        uint64_t from, uint64_t to) {
            const size_t at = c.decompressPart(file, keptSection, from * sizeof(float),
                                               to * sizeof(float), true, *window);
            return reinterpret_cast<const float*>(window->data() + at);
        };
        const uint64_t windowChunks =
            std::max<uint64_t>(4, tbb::this_task_arena::max_concurrency());
        grid = joinAprons(builder, std::move(masks), c.ch.apronCount, read,
                          windowChunks * c.ch.chunkBytes / sizeof(float), path);
    }
    if (c.ch.texKind)
        grid.setExpandedTexcoords(static_cast<TexcoordKind>(c.ch.texKind), texcoords, path);
    return grid;
}

}  // namespace

namespace {

Grid readSdfg(const std::string& path) {
    const MappedFile file(path, MappedFile::Load::Lazy);  // each piece released once read
    const uint64_t fileBytes = file.size();
    const Header h = readHeader(file, path);
    const GridShape s = shapeOf(h, path);
    if (h.version >= 3) return loadCompressed(file, h, s, path);
    const PayloadLayout l = layoutOf(h, s, path, fileBytes);
    checkMemoryBudget(2.0 * static_cast<double>(l.bytes), path,
                      "the grid's samples and the structures built from them",
                      "convert or bake it at a lower resolution");

    uint64_t pos = sizeof h;
    auto readExact = [&](void* dst, size_t bytes) {
        if (bytes > fileBytes - pos) throw InputError(path + ": truncated payload");
        if (bytes) std::memcpy(dst, file.data() + pos, bytes);
        file.release(pos, bytes);
        pos += bytes;
    };
    uint64_t sum = 0xcbf29ce484222325ull;
    std::vector<float> samples;
    std::vector<uint8_t> flags;
    if (l.kind == GridKind::Dense) {
        samples.resize(s.vertexCount());
    } else {
        flags.resize(l.numBlocks);
        readExact(flags.data(), l.numBlocks);
        sum = fnv1a64(flags.data(), flags.size(), sum);
        samples.resize((l.bytes - l.numBlocks - l.texHeaderBytes) / l.floatsPerSample /
                       sizeof(float));
    }
    readExact(samples.data(), samples.size() * sizeof(float));
    sum = fnv1a64(samples.data(), samples.size() * sizeof(float), sum);
    uint32_t texHeader[2] = {0, 0};
    std::vector<float> texcoords;
    if (l.texcoords) {
        readExact(texHeader, sizeof texHeader);
        texcoords.resize(3 * samples.size());
        readExact(texcoords.data(), texcoords.size() * sizeof(float));
        sum = fnv1a64(texHeader, sizeof texHeader, sum);
        sum = fnv1a64(texcoords.data(), texcoords.size() * sizeof(float), sum);
    }
    if (sum != h.checksum) throw InputError(path + ": corrupt: payload checksum mismatch");
    if (!allFinite(samples.data(), samples.size()))
        throw InputError(path + ": corrupt: non-finite sample");
    if (l.texcoords && texHeader[0] != static_cast<uint32_t>(TexcoordKind::Sphere) &&
        texHeader[0] != static_cast<uint32_t>(TexcoordKind::Cylinder)) {
        throw InputError(path + ": unknown texture-coordinate kind " +
                         std::to_string(texHeader[0]) + " (accepted: 1 sphere, 2 cylinder)");
    }
    Grid grid = l.kind == GridKind::Dense
                    ? Grid::dense(s, std::move(samples))
                    : Grid::sparseFromBuffers(s, static_cast<int>(h.blockSize), h.background,
                                              std::move(flags), std::move(samples), path);
    if (l.texcoords)
        grid.setExpandedTexcoords(static_cast<TexcoordKind>(texHeader[0]), texcoords, path);
    return grid;
}

}  // namespace

Grid loadSdfg(const std::string& path) {
    return readWithinBudget(path, [&] { return readSdfg(path); });
}

SdfgSummary readSdfgSummary(const std::string& path) {
    const MappedFile file(path, MappedFile::Load::Lazy);  // the header and tables alone are read
    const Header h = readHeader(file, path);
    SdfgSummary r;
    r.version = h.version;
    r.kind = static_cast<GridKind>(h.kind);
    r.shape = shapeOf(h, path);
    r.fileBytes = file.size();
    BlockTable table;
    uint64_t extraBlocks = 0;
    if (h.version >= 3) {
        const Compressed c(file, h, r.shape, path);
        r.texcoords = static_cast<TexcoordKind>(c.ch.texKind);
        if (r.kind == GridKind::Sparse) table = c.blockTable(file, h, r.shape, path);
        if (h.version >= 5) extraBlocks = c.ch.apronCount;  // the apron blocks, stored
    } else {
        const PayloadLayout l = layoutOf(h, r.shape, path, file.size());
        if (l.kind == GridKind::Sparse) {
            int blocks[3];
            blocksOf(r.shape, static_cast<int>(h.blockSize), blocks);
            const uint8_t* flags = reinterpret_cast<const uint8_t*>(file.data()) + sizeof h;
            table = BlockTable::fromDense(blocks, std::vector<uint8_t>(flags, flags + l.numBlocks),
                                          path);
        }
        if (l.texcoords) {  // its kind follows the samples
            const uint64_t samples = (l.bytes - l.numBlocks - l.texHeaderBytes) / 16;
            uint32_t kind = 0;
            std::memcpy(&kind, file.data() + sizeof h + l.numBlocks + 4 * samples, sizeof kind);
            if (kind != static_cast<uint32_t>(TexcoordKind::Sphere) &&
                kind != static_cast<uint32_t>(TexcoordKind::Cylinder))
                throw InputError(path + ": unknown texture-coordinate kind " +
                                 std::to_string(kind) + " (accepted: 1 sphere, 2 cylinder)");
            r.texcoords = static_cast<TexcoordKind>(kind);
        }
    }
    if (r.kind == GridKind::Dense) {
        r.sampleBytes = r.shape.vertexCount() * sizeof(float);
        r.memoryBytes = r.sampleBytes;
    } else {
        r.blockSize = static_cast<int>(h.blockSize);
        r.background = h.background;
        r.blocks = countBlocks(table.blocks, table.tiles, table.tilePage, table.flags);
        const uint64_t B = h.blockSize;
        r.sampleBytes = r.blocks.surface * B * B * B * sizeof(float);
        r.memoryBytes = Grid::sparseMemoryEstimate(table, r.blocks.surface, r.blockSize) +
                        extraBlocks * (B * B * B * sizeof(float) + sizeof(int32_t) + 1);
    }
    return r;
}

}  // namespace sdft
