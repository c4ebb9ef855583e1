#include "sdftrace/io/sdfg_io.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/io/atomic_file.h"

namespace sdft {

namespace {

constexpr char kMagic[4] = {'S', 'D', 'F', 'G'};
constexpr int kMaxCells = 32768;

// Fixed 64-byte header; all fields little-endian (the formats supported are little-endian hosts).
struct Header {
    char magic[4];
    uint32_t version;
    uint32_t kind;
    int32_t cells[3];
    float origin[3];
    float voxelSize;
    uint32_t blockSize;
    float background;
    uint64_t payloadBytes;
    uint64_t checksum;
};
static_assert(sizeof(Header) == 64, "the .sdfg header is 64 bytes");

struct File {
    FILE* f;
    ~File() {
        if (f) std::fclose(f);
    }
};

}  // namespace

uint64_t fnv1a64(const void* data, size_t bytes, uint64_t h) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) {
        h ^= p[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

void saveSdfg(const Grid& grid, const std::string& path) {
    const GridShape& s = grid.shape();
    Header h{};
    std::memcpy(h.magic, kMagic, 4);
    const bool tex = !grid.texcoords().empty();
    h.version = tex ? 2 : 1;
    h.kind = static_cast<uint32_t>(grid.kind());
    for (int a = 0; a < 3; ++a) {
        h.cells[a] = s.cells[a];
        h.origin[a] = s.origin[a];
    }
    h.voxelSize = s.voxelSize;
    h.blockSize = grid.kind() == GridKind::Sparse ? grid.blockSize() : 0;
    h.background = grid.background();
    uint64_t sum = 0xcbf29ce484222325ull;
    if (grid.kind() == GridKind::Dense) {
        h.payloadBytes = grid.samples().size() * sizeof(float);
        sum = fnv1a64(grid.samples().data(), h.payloadBytes, sum);
    } else {
        h.payloadBytes = grid.flags().size() + grid.blockSamples().size() * sizeof(float);
        sum = fnv1a64(grid.flags().data(), grid.flags().size(), sum);
        sum = fnv1a64(grid.blockSamples().data(), grid.blockSamples().size() * sizeof(float), sum);
    }
    const uint32_t texHeader[2] = {static_cast<uint32_t>(grid.texcoordKind()), 0};
    if (tex) {
        h.payloadBytes += sizeof texHeader + grid.texcoords().size() * sizeof(float);
        sum = fnv1a64(texHeader, sizeof texHeader, sum);
        sum = fnv1a64(grid.texcoords().data(), grid.texcoords().size() * sizeof(float), sum);
    }
    h.checksum = sum;

    AtomicOutput out(path);
    out.write(&h, sizeof h);
    if (grid.kind() == GridKind::Dense) {
        out.write(grid.samples().data(), grid.samples().size() * sizeof(float));
    } else {
        out.write(grid.flags().data(), grid.flags().size());
        out.write(grid.blockSamples().data(), grid.blockSamples().size() * sizeof(float));
    }
    if (tex) {
        out.write(texHeader, sizeof texHeader);
        out.write(grid.texcoords().data(), grid.texcoords().size() * sizeof(float));
    }
    out.commit();
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

Header readHeader(std::FILE* f, const std::string& path, uint64_t fileBytes) {
    Header h{};
    if (fileBytes < sizeof h || std::fread(&h, sizeof h, 1, f) != 1) {
        throw InputError(path + ": truncated: shorter than the 64-byte .sdfg header");
    }
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
        if (h.blockSize != 4 && h.blockSize != 8)
            throw InputError(path + ": block size " + std::to_string(h.blockSize) +
                             " (accepted: 4, 8)");
        if (!(h.background > 0) || !std::isfinite(h.background))
            throw InputError(path + ": background must be positive and finite");
        for (int a = 0; a < 3; ++a)
            l.numBlocks =
                (a == 0 ? 1 : l.numBlocks) * ((s.cells[a] + h.blockSize - 1) / h.blockSize);
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
    checkMemoryBudget(2.0 * static_cast<double>(l.bytes), path,
                      "the grid's samples and the structures built from them",
                      "convert or bake it at a lower resolution");
    return l;
}

}  // namespace

Grid loadSdfg(const std::string& path) {
    File file{std::fopen(path.c_str(), "rb")};
    if (!file.f)
        throw InputError(path + ": cannot open grid file (does it exist and is it readable?)");
    std::error_code ec;
    uint64_t fileBytes = std::filesystem::file_size(path, ec);
    if (ec) throw InputError(path + ": cannot read the file size");
    const Header h = readHeader(file.f, path, fileBytes);
    const GridShape s = shapeOf(h, path);
    const PayloadLayout l = layoutOf(h, s, path, fileBytes);

    auto readExact = [&](void* dst, size_t bytes) {
        if (bytes && std::fread(dst, 1, bytes, file.f) != bytes)
            throw InputError(path + ": truncated payload");
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
    for (float v : samples)
        if (!std::isfinite(v)) throw InputError(path + ": corrupt: non-finite sample");
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
        grid.setTexcoords(static_cast<TexcoordKind>(texHeader[0]), std::move(texcoords), path);
    return grid;
}

}  // namespace sdft
