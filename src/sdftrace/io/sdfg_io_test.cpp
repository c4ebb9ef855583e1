#include "sdftrace/io/sdfg_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "sdftrace/core/error.h"
#include "sdftrace/field/sample_grid.h"
#include "test_files.h"

namespace sdft {
namespace {

using testing::tempPath;

Grid makeGrid(GridKind kind) {
    Tape tape = compileTape(node::torus(0.7f, 0.2f), {.boundsCulling = false});
    SampleOptions o;
    o.resolution = 40;
    o.kind = kind;
    return sampleGrid(tape, nodeBounds(*node::torus(0.7f, 0.2f)), o);
}

std::string readAll(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}
void writeAll(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary) << bytes;
}

// Versions 4 (the default: the block table by tiles), 3 (flat block flags, compressed) and 1
// (raw) give back the same grid.
TEST(Sdfg, RoundTripIsExactForBothLayoutsInEveryVersion) {
    for (uint32_t written : {5u, 4u, 3u, 1u})
        for (GridKind kind : {GridKind::Dense, GridKind::Sparse}) {
            Grid g = makeGrid(kind);
            std::string path = tempPath("rt.sdfg");
            saveSdfg(g, path, {.compress = written != 1, .version = written == 1 ? 4u : written});
            uint32_t version = 0;
            std::memcpy(&version, readAll(path).data() + 4, 4);
            // Version 5 stores sparse grids; dense ones stay version 4.
            EXPECT_EQ(version, written == 5 && kind == GridKind::Dense ? 4u : written);
            Grid back = loadSdfg(path);
            EXPECT_EQ(back.kind(), kind);
            EXPECT_EQ(back.samples(), g.samples());
            EXPECT_EQ(back.flags(), g.flags());
            EXPECT_EQ(back.expandedBlockSamples(), g.expandedBlockSamples());
            EXPECT_EQ(back.cellMasks(), g.cellMasks());
            EXPECT_EQ(back.lipschitz(), g.lipschitz());
            EXPECT_EQ(back.shape().voxelSize, g.shape().voxelSize);
            // The derived tables, stored (version 5) or recomputed, are the grid's.
            EXPECT_EQ(back.blockSamples(), g.blockSamples());
            EXPECT_EQ(back.blockNeighbors(), g.blockNeighbors());
            EXPECT_EQ(back.blockSkip(), g.blockSkip());
            EXPECT_EQ(back.tileSkip(), g.tileSkip());
            EXPECT_EQ(back.blockLipschitz(), g.blockLipschitz());
            EXPECT_EQ(back.tileLipschitz(), g.tileLipschitz());
            EXPECT_EQ(back.gentleLipschitz(), g.gentleLipschitz());
            EXPECT_EQ(back.memoryBytes(), g.memoryBytes());
            std::filesystem::remove(path);
        }
}

// Version 2 stores texture coordinates beside the distances; grids without them stay version 1.
TEST(Sdfg, TextureCoordinatesRoundTripAsVersionTwo) {
    for (GridKind kind : {GridKind::Dense, GridKind::Sparse}) {
        Grid g = makeGrid(kind);
        std::string path = tempPath("v1.sdfg");
        const SdfgWriteOptions raw{.compress = false};
        saveSdfg(g, path, raw);
        uint32_t version = 0;
        std::memcpy(&version, readAll(path).data() + 4, 4);
        EXPECT_EQ(version, 1u);
        std::vector<float> tex(3 * g.storedSamples());
        for (size_t i = 0; i < tex.size(); ++i) tex[i] = 0.001f * static_cast<float>(i % 997);
        g.setTexcoords(TexcoordKind::Cylinder, tex, "test");
        // Every vertex's own vector is kept; a sparse grid's samples without a vertex of their
        // own (shared constant blocks) carry none.
        const size_t owned = kind == GridKind::Dense ? tex.size()
                                                     : 3 * g.surfaceBlockCount() * g.blockSize() *
                                                           g.blockSize() * g.blockSize();
        ASSERT_TRUE(std::equal(tex.begin(), tex.begin() + owned, g.texcoords().begin()));
        tex = g.texcoords();
        // Compressed (versions 4 and 3) with texture coordinates.
        for (uint32_t v : {4u, 3u}) {
            saveSdfg(g, path, {.version = v});
            Grid packed = loadSdfg(path);
            EXPECT_EQ(packed.texcoordKind(), TexcoordKind::Cylinder);
            EXPECT_EQ(packed.texcoords(), tex);
            EXPECT_EQ(packed.expandedBlockSamples(), g.expandedBlockSamples());
        }
        saveSdfg(g, path, raw);
        std::memcpy(&version, readAll(path).data() + 4, 4);
        EXPECT_EQ(version, 2u);
        Grid back = loadSdfg(path);
        EXPECT_EQ(back.texcoordKind(), TexcoordKind::Cylinder);
        EXPECT_EQ(back.texcoords(), tex);
        EXPECT_EQ(back.samples(), g.samples());
        EXPECT_EQ(back.expandedBlockSamples(), g.expandedBlockSamples());
        // A flipped texture-coordinate byte fails the checksum.
        std::string bytes = readAll(path);
        bytes[bytes.size() - 5] ^= 0x10;
        writeAll(path, bytes);
        EXPECT_THROW(loadSdfg(path), InputError);
        std::filesystem::remove(path);
    }
    Grid g = makeGrid(GridKind::Dense);
    EXPECT_THROW(g.setTexcoords(TexcoordKind::Sphere, std::vector<float>(5), "test"), InputError);
}

void expectRejected(const std::string& bytes, const std::string& fragment) {
    std::string path = tempPath("bad.sdfg");
    writeAll(path, bytes);
    try {
        loadSdfg(path);
        ADD_FAILURE() << "accepted a bad file; expected: " << fragment;
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
    std::filesystem::remove(path);
}

TEST(Sdfg, RejectsBadFilesBeforeAllocating) {
    std::string path = tempPath("good.sdfg");
    saveSdfg(makeGrid(GridKind::Sparse), path, {.compress = false});
    std::string good = readAll(path);
    std::filesystem::remove(path);

    expectRejected("", "truncated");
    expectRejected(good.substr(0, 40), "truncated");
    expectRejected(good.substr(0, good.size() - 10), "truncated");
    expectRejected(good + "xx", "trailing bytes");
    std::string magic = good;
    magic[0] = 'X';
    expectRejected(magic, "bad magic");
    std::string version = good;
    uint32_t v = 99;
    std::memcpy(&version[4], &v, 4);
    expectRejected(version, "version 99");
    std::string corrupt = good;
    corrupt[good.size() - 3] ^= 0x55;
    expectRejected(corrupt, "checksum");
    // An absurd size in the header: rejected from the header and the file size, not by allocating.
    std::string absurd = good;
    int32_t huge = 30000;
    for (int a = 0; a < 3; ++a) std::memcpy(&absurd[12 + 4 * a], &huge, 4);
    expectRejected(absurd, "payload size");
    std::string tooBig = good;
    int32_t over = 1 << 20;
    std::memcpy(&tooBig[12], &over, 4);
    expectRejected(tooBig, "out of range");
    std::string block = good;
    uint32_t five = 5;
    std::memcpy(&block[40], &five, 4);
    expectRejected(block, "block size 5");
}

// Versions 3 and 4: every table and chunk is checked against the header, the file and its
// checksums.
TEST(Sdfg, RejectsBadCompressedFiles) {
    for (uint32_t version : {3u, 4u, 5u}) {
        std::string path = tempPath("good3.sdfg");
        saveSdfg(makeGrid(GridKind::Sparse), path, {.version = version});
        std::string good = readAll(path);
        std::filesystem::remove(path);
        const size_t table = 64 + 32 + (version == 5 ? 24 : version == 4 ? 8 : 0);  // chunk table
        ASSERT_GT(good.size(), table + 8);

        expectRejected(good.substr(0, 40), "truncated");
        expectRejected(good.substr(0, good.size() - 10), "payload size");
        expectRejected(good + "xx", "payload size");
        std::string chunk = good;
        chunk[good.size() - 6] ^= 0x55;
        // The last chunk is named (versions 3 and 4: the explicit aprons; 5: the tiles' Lipschitz
        // codes).
        uint64_t chunks = 0;
        std::memcpy(&chunks, good.data() + 64 + 24, 8);
        expectRejected(chunk, "chunk " + std::to_string(chunks - 1) + " (");
        std::string badTable = good;
        badTable[table] ^= 0x01;
        expectRejected(badTable, "table checksum");
        std::string chunkSize = good;
        uint32_t odd = 4097;
        std::memcpy(&chunkSize[64 + 4], &odd, 4);
        expectRejected(chunkSize, "chunk size");
        // Absurd cells: the chunk count no longer follows, rejected before any allocation.
        std::string absurd = good;
        int32_t huge = 30000;
        for (int a = 0; a < 3; ++a) std::memcpy(&absurd[12 + 4 * a], &huge, 4);
        expectRejected(absurd, "chunk count");
        std::string count = good;
        uint64_t many = uint64_t{1} << 40;
        std::memcpy(&count[64 + 24], &many, 8);
        expectRejected(count, "chunk count");
        if (version == 5) {  // a surface block count the flags do not give
            std::string surface = good;
            uint64_t one = 1;
            std::memcpy(&surface[64 + 32 + 8], &one, 8);
            expectRejected(surface, "");
        }
        if (version >= 4) {
            std::string pages = good;
            std::memcpy(&pages[64 + 32], &many, 8);
            expectRejected(pages, "own page count");
        }
    }
}

// What `info` prints without loading: the header and tables agree with the grid they load into,
// and no sample is read (a damaged sample chunk goes unnoticed until the grid is loaded; a damaged
// table does not).
TEST(Sdfg, SummaryReadsTheHeaderAndTablesAlone) {
    for (uint32_t written : {5u, 4u, 3u, 1u})
        for (GridKind kind : {GridKind::Dense, GridKind::Sparse})
            for (int B : {4, 8}) {
                if (kind == GridKind::Dense && B == 8) continue;
                Tape tape = compileTape(node::torus(0.7f, 0.2f), {.boundsCulling = false});
                SampleOptions o;
                o.resolution = 48;
                o.kind = kind;
                o.blockSize = B;
                Grid g = sampleGrid(tape, nodeBounds(*node::torus(0.7f, 0.2f)), o);
                if (written >= 4)
                    g.setTexcoords(TexcoordKind::Sphere,
                                   std::vector<float>(3 * g.storedSamples(), 0.5f), "t");
                const std::string path = tempPath("summary.sdfg");
                saveSdfg(g, path,
                         {.compress = written != 1, .version = written == 1 ? 4u : written});
                const SdfgSummary r = readSdfgSummary(path);
                const Grid back = loadSdfg(path);
                const std::string what = std::to_string(written) + " " + std::to_string(B);
                // Version 5 stores sparse grids; dense ones stay version 4.
                const uint32_t stored = written == 5 && kind == GridKind::Dense ? 4u : written;
                EXPECT_EQ(r.version, stored) << what;
                EXPECT_EQ(r.kind, kind) << what;
                EXPECT_EQ(r.texcoords, back.texcoordKind()) << what;
                EXPECT_EQ(r.fileBytes, std::filesystem::file_size(path)) << what;
                for (int a = 0; a < 3; ++a) EXPECT_EQ(r.shape.cells[a], g.shape().cells[a]);
                EXPECT_EQ(r.shape.voxelSize, g.shape().voxelSize);
                // Every term but the few shared apron blocks the loader adds.
                EXPECT_LE(r.memoryBytes, back.memoryBytes()) << what;
                EXPECT_GE(r.memoryBytes, 0.97 * back.memoryBytes()) << what;
                if (stored == 5) EXPECT_EQ(r.memoryBytes, back.memoryBytes()) << what;  // stored
                if (kind == GridKind::Sparse) {
                    size_t in = 0, out = 0, surf = 0;
                    back.blockCounts(in, out, surf);
                    EXPECT_EQ(r.blocks.surface, surf) << what;
                    EXPECT_EQ(r.blocks.inside, in) << what;
                    EXPECT_EQ(r.blocks.outside, out) << what;
                    EXPECT_EQ(r.blockSize, B);
                    EXPECT_EQ(r.background, g.background());
                    EXPECT_EQ(r.sampleBytes, surf * B * B * B * sizeof(float));
                } else {
                    EXPECT_EQ(r.sampleBytes, g.samples().size() * sizeof(float));
                }
                if (written >= 4 && kind == GridKind::Sparse) {
                    // The last chunk (texture coordinates) damaged: described, not loaded.
                    std::string bytes = readAll(path);
                    bytes[bytes.size() - 6] ^= 0x55;
                    writeAll(path, bytes);
                    EXPECT_NO_THROW(readSdfgSummary(path));
                    EXPECT_THROW(loadSdfg(path), InputError);
                    // The first (the tile kinds) damaged: neither.
                    bytes = readAll(path);
                    uint64_t chunks = 0, first = 0;
                    const size_t table = 64 + 32 + (written == 5 ? 24 : 8);
                    std::memcpy(&chunks, bytes.data() + 64 + 24, 8);
                    std::memcpy(&first, bytes.data() + table, 8);
                    bytes[table + 8 * chunks + first / 2] ^= 0x55;
                    writeAll(path, bytes);
                    EXPECT_THROW(readSdfgSummary(path), InputError);
                }
                std::filesystem::remove(path);
            }
    EXPECT_THROW(readSdfgSummary(tempPath("missing.sdfg")), InputError);
}

TEST(Sdfg, FailedSaveLeavesNoFile) {
    EXPECT_THROW(saveSdfg(makeGrid(GridKind::Dense), "/nonexistent-dir/x.sdfg"), InputError);
}

}  // namespace
}  // namespace sdft
