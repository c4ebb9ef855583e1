// The distributed exact bake's pieces in one process: slabs baked apart and assembled are the
// whole bake bit for bit (what mpirun relies on; tests/cluster_test.cpp runs it across ranks).
#include "sdftrace/cluster/distributed_bake.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "sdftrace/bake/exact_slab.h"
#include "sdftrace/bake/test_meshes.h"
#include "sdftrace/field/block_table.h"
#include "sdftrace/io/block_aprons.h"
#include "sdftrace/io/grid_file.h"
#include "sdftrace/io/mesh_io.h"

namespace sdft {
namespace {

// The grid's file, the byte-exact form of everything it holds.
std::string fileBytes(const Grid& grid, const std::string& name) {
    const std::string path =
        (std::filesystem::temp_directory_path() / ("sdftrace-slab-test-" + name + ".sdfg"))
            .string();
    saveGridFile(grid, path);
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::filesystem::remove(path);
    return bytes;
}

struct Case {
    std::string name;
    TriangleMesh mesh;
    int resolution, block;
    float band;
    SignMethod sign;
};

TEST(DistributedBake, SlabsAssembleIntoTheWholeBakeBitForBit) {
    const std::string meshes = std::string(SDFT_SOURCE_DIR) + "/data/meshes/";
    std::vector<Case> cases;
    cases.push_back(
        {"torus", testing::torusMesh(1, 0.35f, 48, 24), 40, 4, 3, SignMethod::WindingNumber});
    cases.push_back({"elephant", loadMesh(meshes + "elephant-with-holes.obj"), 48, 8, 4,
                     SignMethod::WindingNumber});  // open: closing films
    cases.push_back({"teapot", loadMesh(meshes + "teapot.obj"), 36, 4, 2, SignMethod::RayParity});
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        SampleOptions o;
        o.resolution = c.resolution;
        const GridShape shape = gridShapeFor(c.mesh.bounds(), o);
        const std::string whole = fileBytes(
            bakeExactSparse(c.mesh, shape, c.block, c.band, c.sign, 2), c.name + "-whole");
        const int layers = (shape.cells[2] + c.block - 1) / c.block;
        for (int count : {1, 2, 3, 5, layers + 3}) {
            SCOPED_TRACE(count);
            const std::vector<BlockSlab> slabs =
                balancedSlabs(c.mesh, shape, c.block, c.band, count);
            ASSERT_EQ(slabs.size(), static_cast<size_t>(count));
            std::vector<SlabSamples> baked;
            for (const BlockSlab& s : slabs)
                if (s.last > s.first)
                    baked.push_back(bakeExactSlab(c.mesh, shape, c.block, c.band, c.sign, s, 1));
            std::vector<const SlabSamples*> parts;
            for (const SlabSamples& s : baked) parts.push_back(&s);
            const Grid grid = assembleExactSlabs(shape, c.block, c.band, parts, 2);
            EXPECT_TRUE(fileBytes(grid, c.name) == whole);
        }
    }
}

TEST(DistributedBake, SlabsCoverTheLayersInOrderAndShareTheWork) {
    const TriangleMesh mesh =
        loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/stanford-bunny.obj");
    SampleOptions o;
    o.resolution = 128;
    const GridShape shape = gridShapeFor(mesh.bounds(), o);
    const int layers = (shape.cells[2] + 3) / 4;
    for (int count : {1, 2, 4, 7}) {
        const std::vector<BlockSlab> slabs = balancedSlabs(mesh, shape, 4, 3, count);
        int at = 0;
        std::vector<size_t> blocks;
        for (const BlockSlab& s : slabs) {
            EXPECT_EQ(s.first, at);
            EXPECT_GT(s.last, s.first);  // 32 layers: none empty
            at = s.last;
            // The work a slab holds: its surface blocks.
            blocks.push_back(
                bakeExactSlab(mesh, shape, 4, 3, SignMethod::WindingNumber, s, 2).samples.size());
        }
        EXPECT_EQ(at, layers);
        const auto [lo, hi] = std::minmax_element(blocks.begin(), blocks.end());
        // Balanced by triangles near each layer: within a factor of two of each other.
        EXPECT_LE(*hi, 2 * *lo + 125 * 40) << count << " slabs";
    }
}

TEST(DistributedBake, TileSlabsStartOnTileLayersCoverTheGridAndAreNeverEmpty) {
    const TriangleMesh mesh =
        loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/stanford-bunny.obj");
    for (int resolution : {20, 128, 300}) {
        SampleOptions o;
        o.resolution = resolution;
        const GridShape shape = gridShapeFor(mesh.bounds(), o);
        const int layers = (shape.cells[2] + 3) / 4;
        const int tiles = (layers + kTileBlocks - 1) / kTileBlocks;
        for (int count : {1, 2, 3, 7, tiles + 3}) {
            SCOPED_TRACE(std::to_string(resolution) + " cells, " + std::to_string(count));
            const std::vector<BlockSlab> slabs = tileSlabs(mesh, shape, 4, 3, count);
            EXPECT_EQ(slabs.size(), static_cast<size_t>(std::min(count, tiles)));
            int at = 0;
            for (const BlockSlab& s : slabs) {
                EXPECT_EQ(s.first, at);
                EXPECT_EQ(s.first % kTileBlocks, 0);
                EXPECT_GT(s.last, s.first);
                at = s.last;
            }
            EXPECT_EQ(at, layers);
        }
    }
}

// Slabs split into a .sdfg's sections apart, each told the flags of the layer past it, join into
// exactly what the version-4 writer makes of the whole bake: its surface blocks' own samples, the
// apron masks and the kept apron samples.
TEST(DistributedBake, SlabSectionsJoinIntoTheWholeGridsSections) {
    const std::string meshes = std::string(SDFT_SOURCE_DIR) + "/data/meshes/";
    std::vector<Case> cases;
    cases.push_back({"elephant", loadMesh(meshes + "elephant-with-holes.obj"), 150, 4, 3,
                     SignMethod::WindingNumber});
    cases.push_back({"teapot", loadMesh(meshes + "teapot.obj"), 200, 8, 4, SignMethod::RayParity});
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        SampleOptions o;
        o.resolution = c.resolution;
        const GridShape shape = gridShapeFor(c.mesh.bounds(), o);
        const Grid whole = bakeExactSparse(c.mesh, shape, c.block, c.band, c.sign, 2);
        const ApronSamples aprons = splitAprons(whole);
        const size_t own = whole.surfaceBlockCount() * c.block * c.block * c.block;
        const std::vector<float> wholeOwn(whole.blockSamples().begin(),
                                          whole.blockSamples().begin() + own);
        for (int count : {2, 3}) {
            const std::vector<BlockSlab> slabs = tileSlabs(c.mesh, shape, c.block, c.band, count);
            ASSERT_GE(slabs.size(), 2u);
            // Each slab's first layer, as the next rank would send it.
            std::vector<std::vector<uint8_t>> first(slabs.size());
            for (size_t i = 1; i < slabs.size(); ++i) {
                const SlabSamples s =
                    bakeExactSlab(c.mesh, shape, c.block, c.band, c.sign, slabs[i], 2);
                first[i].assign(
                    s.flags.begin(),
                    s.flags.begin() + s.flags.size() / (slabs[i].last - slabs[i].first));
            }
            std::vector<float> joinedOwn, kept;
            std::vector<uint64_t> masks;
            for (size_t i = 0; i < slabs.size(); ++i) {
                const SlabSections s = bakeExactSlabSections(
                    c.mesh, shape, c.block, c.band, c.sign, slabs[i],
                    [&](const std::vector<uint8_t>& mine) {
                        if (i > 0) {
                            EXPECT_EQ(mine, first[i]);
                        }
                        return i + 1 < slabs.size() ? first[i + 1] : std::vector<uint8_t>();
                    },
                    2);
                joinedOwn.insert(joinedOwn.end(), s.own.begin(), s.own.end());
                masks.insert(masks.end(), s.apronMasks.begin(), s.apronMasks.end());
                kept.insert(kept.end(), s.kept.begin(), s.kept.end());
            }
            EXPECT_TRUE(joinedOwn == wholeOwn) << count << " slabs";
            EXPECT_TRUE(masks == aprons.masks) << count << " slabs";
            EXPECT_TRUE(kept == aprons.explicitly) << count << " slabs";
        }
    }
}

// One process through the path every rank takes under mpirun: the file it writes loads as the
// single-process bake's grid.
TEST(DistributedBake, ABakeWrittenByOneRankLoadsAsTheWholeBake) {
    const TriangleMesh mesh =
        loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/stanford-bunny.obj");
    MeshBakeOptions o;
    o.method = MeshBakeMethod::Exact;
    o.sampling.kind = GridKind::Sparse;
    o.sampling.resolution = 200;
    o.sampling.threads = 2;
    const GridShape shape = gridShapeFor(mesh.bounds(), o.sampling);
    const std::string path =
        (std::filesystem::temp_directory_path() / "sdftrace-one-rank-bake.sdfg").string();
    const DistributedBakeSummary sum = bakeExactToSdfg(Communicator::world(), mesh, o, path, 3);
    const Grid whole =
        bakeExactSparse(mesh, shape, o.sampling.blockSize, o.sampling.bandVoxels, o.sign, 2);
    EXPECT_EQ(sum.surface, whole.surfaceBlockCount());
    EXPECT_EQ(sum.fileBytes, std::filesystem::file_size(path));
    const std::string written = fileBytes(loadGridFile(path), "one-rank");
    std::filesystem::remove(path);
    EXPECT_TRUE(written == fileBytes(whole, "whole"));
}

// The wrong slabs are refused rather than assembled into a wrong grid.
TEST(DistributedBake, AssemblyRefusesSlabsThatDoNotCoverTheGrid) {
    const TriangleMesh mesh = testing::torusMesh(1, 0.35f, 32, 16);
    SampleOptions o;
    o.resolution = 32;
    const GridShape shape = gridShapeFor(mesh.bounds(), o);
    const std::vector<BlockSlab> slabs = balancedSlabs(mesh, shape, 4, 3, 2);
    const SlabSamples first =
        bakeExactSlab(mesh, shape, 4, 3, SignMethod::WindingNumber, slabs[0], 1);
    EXPECT_THROW(assembleExactSlabs(shape, 4, 3, {&first}, 1), std::runtime_error);
}

}  // namespace
}  // namespace sdft
