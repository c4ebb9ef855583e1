// The distributed exact bake's pieces in one process: slabs baked apart and assembled are the
// whole bake bit for bit (what mpirun relies on; tests/cluster_test.cpp runs it across ranks).
#include "sdftrace/cluster/distributed_bake.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "sdftrace/bake/test_meshes.h"
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
