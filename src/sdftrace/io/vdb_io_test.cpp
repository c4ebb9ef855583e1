#include "sdftrace/io/vdb_io.h"

#include <gtest/gtest.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/test_util.h"
#include "sdftrace/io/grid_file.h"
#include "sdftrace/io/sdfg_io.h"
#include "sdftrace/trace/grid_tracer.h"
#include "test_files.h"
#include "vdb_reader.h"

namespace sdft {
namespace {

using testing::tempPath;

Grid torusGrid(GridKind kind) {
    NodePtr n = node::unite(
        {node::torus(0.7f, 0.2f), node::translate(node::sphere(0.3f), {0.2f, 0.3f, 0})});
    Tape tape = compileTape(n, {.boundsCulling = false});
    SampleOptions o;
    o.resolution = 48;
    o.kind = kind;
    return sampleGrid(tape, nodeBounds(*n), o);
}

// .sdfg -> .vdb -> .sdfg keeps every sample in the band exactly (floats are stored as floats)
// and the sign everywhere.
TEST(Vdb, RoundTripKeepsTheBandExactlyAndTheSignEverywhere) {
    for (GridKind kind : {GridKind::Sparse, GridKind::Dense}) {
        Grid original = torusGrid(kind);
        std::string vdb = tempPath("rt.vdb"), back = tempPath("rt.sdfg");
        saveGridFile(original, vdb);
        saveGridFile(loadGridFile(vdb), back);
        Grid again = loadGridFile(back);
        GridView a = original.view(), b = again.view();
        const float h = original.shape().voxelSize;
        ASSERT_EQ(again.shape().voxelSize, h);
        testing::Rng rng(5);
        Bounds3 region = again.shape().bounds();
        int inBand = 0;
        for (int i = 0; i < 20000; ++i) {
            Vec3 p = rng.inBox(region.lo, region.hi);
            float va = a.interpolate(p), vb = b.interpolate(p);
            ASSERT_EQ(va < 0, vb < 0) << i;
            if (std::fabs(va) < 1.5f * h) {
                ASSERT_NEAR(va, vb, 1e-6f) << i;
                ++inBand;
            }
        }
        EXPECT_GT(inBand, 500);
        std::filesystem::remove(vdb);
        std::filesystem::remove(back);
    }
}

// The reader counts the nodes it makes against the memory budget as it reads them: a budget of
// 20 times the file loads it (the tree takes a few times the file; a bound of ~40 times, the
// worst an upper node can cost, refused real level sets), and one under the tree refuses it,
// naming what needed the memory.
TEST(Vdb, TheMemoryBudgetCountsTheTreeAsItIsRead) {
    const std::string vdb = tempPath("budget.vdb");
    saveGridFile(torusGrid(GridKind::Sparse), vdb);
    const double file = static_cast<double>(std::filesystem::file_size(vdb));
    const double before = memoryBudgetIsSet() ? memoryBudgetBytes() : 0;  // 0: the default
    setMemoryBudgetBytes(20 * file);
    EXPECT_NO_THROW(loadGridFile(vdb));
    setMemoryBudgetBytes(1.5 * file);
    try {
        loadGridFile(vdb);
        ADD_FAILURE() << "loaded over the budget";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("the file and its tree"), std::string::npos)
            << e.what();
    }
    setMemoryBudgetBytes(before);
    std::filesystem::remove(vdb);
}

// A level set made by OpenVDB's own tools renders here: it matches the analytic sphere.
TEST(Vdb, ImportsALevelSetMadeByOpenVdb) {
    openvdb::initialize();
    auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        1.0f, openvdb::Vec3f(0.5f, 0, 0), 0.05f, 3.0f);
    std::string path = tempPath("sphere.vdb");
    openvdb::io::File(path).write({sphere});
    Grid g = loadVdb(path);
    GridView v = g.view();
    testing::Rng rng(6);
    for (int i = 0; i < 5000; ++i) {
        Vec3 p = Vec3(0.5f, 0, 0) + rng.direction() * rng.uniform(0.9f, 1.1f);
        EXPECT_NEAR(v.sample(p), length(p - Vec3(0.5f, 0, 0)) - 1.0f, 0.01f);
    }
    size_t in, out, surf;
    g.blockCounts(in, out, surf);
    EXPECT_GT(in, 0u);
    EXPECT_GT(surf, 0u);
    std::filesystem::remove(path);
}

// A level set 8192 voxels across with a small surface (two spheres of radius 12 voxels at
// opposite corners) imports: the importer reads leaves and tiles, the grid pages its tables by
// tiles (block_table.h), so memory follows the surface, never the 8192^3 box. Every voxel the
// level set holds in its band comes back exactly, and rays from afar find both spheres.
TEST(Vdb, ImportsALevelSet8192VoxelsAcross) {
    openvdb::initialize();
    const openvdb::Vec3f centres[2] = {{20, 20, 20}, {8170, 8170, 8170}};
    auto grid =
        openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(12.0f, centres[0], 1.0f, 3.0f);
    auto second =
        openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(12.0f, centres[1], 1.0f, 3.0f);
    grid->tree().merge(second->tree());
    const std::string path = tempPath("far-apart.vdb");
    openvdb::io::File(path).write({grid});
    const Grid g = loadVdb(path);
    std::filesystem::remove(path);
    const GridView v = g.view();
    for (int a = 0; a < 3; ++a) EXPECT_GE(v.shape.cells[a], 8170);
    // 256^3 tiles of 5 bytes and a few dozen pages: well under 200 MiB, where flat block tables
    // of 2048^3 blocks took 43 GiB.
    EXPECT_LT(g.memoryBytes(), size_t{200} << 20);
    size_t in, out, surf;
    g.blockCounts(in, out, surf);
    EXPECT_GT(surf, 0u);
    EXPECT_GT(in, 0u);
    EXPECT_EQ(in + out + surf, static_cast<size_t>(v.blocks[0]) * v.blocks[1] * v.blocks[2]);
    const float band = g.background() + v.shape.voxelSize;
    auto acc = grid->getConstAccessor();
    int compared = 0;
    for (const auto& c : centres)
        for (int z = -16; z <= 16; ++z)
            for (int y = -16; y <= 16; ++y)
                for (int x = -16; x <= 16; ++x) {
                    const openvdb::Coord ijk(static_cast<int>(c.x()) + x,
                                             static_cast<int>(c.y()) + y,
                                             static_cast<int>(c.z()) + z);
                    const float expected = acc.getValue(ijk);
                    if (!(std::fabs(expected) < band)) continue;
                    const Vec3 p(static_cast<float>(ijk.x()), static_cast<float>(ijk.y()),
                                 static_cast<float>(ijk.z()));
                    ASSERT_EQ(v.interpolate(p), expected) << ijk;
                    ++compared;
                }
    EXPECT_GT(compared, 10000);
    testing::Rng rng(3);
    for (int n = 0; n < 200; ++n) {
        const Vec3 centre(centres[n % 2].x(), centres[n % 2].y(), centres[n % 2].z());
        const Vec3 from = Vec3(4096.0f) + rng.direction() * 8000.0f;
        const Vec3 to = centre + rng.inCube(6.0f);
        const GridTraceResult r =
            traceGridRay(v, Ray{from, normalize(to - from)}, 0, 1e6f, GridTraceOptions{});
        ASSERT_TRUE(r.hit) << n;
        EXPECT_NEAR(length(Ray{from, normalize(to - from)}.at(r.t) - centre), 12.0f, 0.5f);
    }
    // As .sdfg (version 4: the block table by tiles): a small file, the same grid back.
    const std::string sdfg = tempPath("far-apart.sdfg");
    saveSdfg(g, sdfg);
    EXPECT_LT(std::filesystem::file_size(sdfg), uintmax_t{16} << 20);
    const Grid back = loadSdfg(sdfg);
    std::filesystem::remove(sdfg);
    EXPECT_EQ(back.tilePage(), g.tilePage());
    EXPECT_EQ(back.flags(), g.flags());
    EXPECT_EQ(back.blockData(), g.blockData());
    EXPECT_EQ(back.expandedBlockSamples(), g.expandedBlockSamples());
    EXPECT_EQ(back.cellMasks(), g.cellMasks());
    EXPECT_EQ(back.tileSkip(), g.tileSkip());
    EXPECT_EQ(back.blockSkip(), g.blockSkip());
}

TEST(Vdb, RejectsUnusableFiles) {
    openvdb::initialize();
    auto expectError = [](const std::string& path, const std::string& fragment) {
        try {
            loadGridFile(path);
            ADD_FAILURE() << "accepted " << path;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
        }
    };
    expectError(tempPath("missing.vdb"), "cannot open");
    std::string garbage = tempPath("garbage.vdb");
    std::ofstream(garbage) << "not a vdb file";
    expectError(garbage, "not an OpenVDB file");
    std::string vec = tempPath("vec.vdb");
    auto v3 = openvdb::Vec3SGrid::create();
    v3->tree().setValue(openvdb::Coord(1, 2, 3), openvdb::Vec3s(1, 0, 0));
    openvdb::io::File(vec).write({v3});
    expectError(vec, "no float grid");
    std::string stretched = tempPath("stretched.vdb");
    auto f =
        openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, openvdb::Vec3f(0), 0.1f);
    auto xf = openvdb::math::Transform::createLinearTransform(0.1);
    xf->postScale(openvdb::Vec3d(1, 2, 1));
    f->setTransform(xf);
    openvdb::io::File(stretched).write({f});
    expectError(stretched, "non-uniform");
    expectError(tempPath("x.obj"), "accepted: .sdfg, .vdb");
    // A NaN or an infinity anywhere in a leaf.
    std::string nan = tempPath("nan.vdb");
    for (float bad : {NAN, INFINITY}) {
        auto g =
            openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, openvdb::Vec3f(0), 0.1f);
        g->tree().setValueOff(openvdb::Coord(10, 0, 0), bad);
        openvdb::io::File(nan).write({g});
        expectError(nan, "non-finite values");
    }
    for (const auto& p : {garbage, vec, stretched, nan}) std::filesystem::remove(p);
}

// Cost follows the file's content: a level set's tiles hold +-background, so a tile of any size
// becomes constant blocks (or a shared constant page), never blocks sampled voxel by voxel; a
// tile inside the band or tiles of opposite sign with no band between them are not a level set
// and are refused before anything is sized by them (a 4096^3 root tile at 0 once took 20 s and
// 1.1 GB to classify, then ran out of budget).
TEST(Vdb, TilesCostWhatTheFileHoldsNotTheVoxelsTheyCover) {
    openvdb::initialize();
    const std::string path = tempPath("tiles.vdb");
    auto write = [&](openvdb::FloatGrid::Ptr g) {
        g->setGridClass(openvdb::GRID_LEVEL_SET);
        openvdb::io::File(path).write({g});
    };
    // A sphere 500 voxels across: OpenVDB fills its inside with tiles at -background, up to
    // 128^3 voxels each; they import as constant blocks, not sampled voxel by voxel.
    {
        auto g = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(250.0f, openvdb::Vec3f(0),
                                                                          1.0f, 3.0f);
        openvdb::Index64 tileVoxels = 0;
        for (auto it = g->tree().cbeginValueAll(); it; ++it)
            if (!it.isVoxelValue() && it.getLevel() >= 2 && *it < 0)
                tileVoxels += it.getBoundingBox().volume();
        ASSERT_GT(tileVoxels, openvdb::Index64{4} << 21);  // several 128^3 tiles
        write(g);
        const Grid grid = loadVdb(path);
        size_t in, out, surf;
        grid.blockCounts(in, out, surf);
        EXPECT_GT(in, tileVoxels / 64);
        // The band: about 4 pi r^2 * 6 voxels / 4^3, well below the sphere's 1.04e6 blocks.
        EXPECT_LT(surf, 150000u);
        EXPECT_LT(grid.memoryBytes(), size_t{96} << 20);
    }
    // Refused, one line each, naming the tile.
    {
        auto g = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(12.0f, openvdb::Vec3f(0),
                                                                          1.0f, 3.0f);
        g->tree().addTile(3, openvdb::Coord(4096, 0, 0), 0.5f, true);
        write(g);
        try {
            loadVdb(path);
            ADD_FAILURE() << "a tile inside the band was accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("tile of 4096^3 voxels at (4096, 0, 0)"),
                      std::string::npos)
                << e.what();
            EXPECT_NE(std::string(e.what()).find("not a level set"), std::string::npos);
        }
        for (int level : {1, 2}) {
            auto h = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
                12.0f, openvdb::Vec3f(0), 1.0f, 3.0f);
            h->tree().addTile(level, openvdb::Coord(256, 0, 0), -0.25f, false);
            write(h);
            EXPECT_THROW(loadVdb(path), InputError) << level;
        }
    }
    {
        // Inside and outside tiles side by side, no leaf between them.
        auto g = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(12.0f, openvdb::Vec3f(0),
                                                                          1.0f, 3.0f);
        g->tree().addTile(2, openvdb::Coord(1024, 0, 0), -g->background(), true);
        g->tree().addTile(2, openvdb::Coord(1152, 0, 0), g->background(), true);
        write(g);
        try {
            loadVdb(path);
            ADD_FAILURE() << "tiles of opposite sign without a band were accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("tiles of opposite sign"), std::string::npos)
                << e.what();
        }
    }
    std::filesystem::remove(path);
}

// The import as it was through OpenVDB's reader: the dense active region, sparsified. The native
// reader must give the same grid, block for block.
Grid importThroughOpenVdb(const openvdb::FloatGrid& grid, const VdbImportOptions& o) {
    openvdb::CoordBBox box = grid.evalActiveVoxelBoundingBox();
    const openvdb::Coord dim = box.dim();
    GridShape shape;
    const float h = static_cast<float>(grid.transform().voxelSize()[0]);
    const openvdb::Vec3d origin = grid.transform().indexToWorld(box.min());
    for (int a = 0; a < 3; ++a) {
        shape.cells[a] = dim[a] - 1;
        shape.origin[a] = static_cast<float>(origin[a]);
    }
    shape.voxelSize = h;
    std::vector<float> samples;
    auto acc = grid.getConstAccessor();
    for (int k = 0; k < dim[2]; ++k)
        for (int j = 0; j < dim[1]; ++j)
            for (int i = 0; i < dim[0]; ++i)
                samples.push_back(acc.getValue(box.min().offsetBy(i, j, k)));
    const float band = std::max(o.minBandVoxels, std::fabs(grid.background()) / h * 0.999f);
    return Grid::sparseFromDense(shape, samples, o.blockSize, band);
}

void expectSameGrid(const Grid& a, const Grid& b, const std::string& what) {
    for (int axis = 0; axis < 3; ++axis) {
        EXPECT_EQ(a.shape().cells[axis], b.shape().cells[axis]) << what;
        EXPECT_FLOAT_EQ(a.shape().origin[axis], b.shape().origin[axis]) << what;
    }
    EXPECT_EQ(a.shape().voxelSize, b.shape().voxelSize) << what;
    EXPECT_EQ(a.background(), b.background()) << what;
    EXPECT_EQ(a.flags(), b.flags()) << what;
    EXPECT_EQ(a.expandedBlockSamples(), b.expandedBlockSamples()) << what;
}

// Level sets and a fog-like grid, written by OpenVDB with every compression it has, in full and
// half precision, as a file (grid offsets) and as a stream (none), after a grid of another type:
// the native reader's tree answers every coordinate as OpenVDB's does, and the imported grid is
// the one the OpenVDB path made.
TEST(Vdb, NativeReaderMatchesOpenVdbOnEveryEncoding) {
    openvdb::initialize();
    auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        0.8f, openvdb::Vec3f(0.3f, -0.2f, 0.1f), 0.05f, 3.0f);
    sphere->setName("sphere");
    // Non-background inactive values, active and inactive tiles, negative coordinates.
    auto fog = openvdb::FloatGrid::create(0.5f);
    fog->setName("fog");
    fog->setTransform(openvdb::math::Transform::createLinearTransform(0.25));
    testing::Rng rng(9);
    for (int i = 0; i < 3000; ++i) {
        const Vec3 p = rng.inCube(40.0f);
        fog->tree().setValue(openvdb::Coord(int(p.x), int(p.y), int(p.z)), rng.uniform(-1, 1));
    }
    for (int i = 0; i < 300; ++i) {
        const Vec3 p = rng.inCube(40.0f);
        fog->tree().setValueOff(openvdb::Coord(int(p.x), int(p.y), int(p.z)), rng.uniform(-2, 2));
    }
    fog->tree().addTile(1, openvdb::Coord(128, 0, 0), -0.75f, true);
    fog->tree().addTile(1, openvdb::Coord(-256, 0, 0), 0.25f, false);
    auto vec = openvdb::Vec3SGrid::create();
    vec->tree().setValue(openvdb::Coord(1, 2, 3), openvdb::Vec3s(1, 0, 0));
    const uint32_t encodings[] = {openvdb::io::COMPRESS_NONE,
                                  openvdb::io::COMPRESS_ZIP,
                                  openvdb::io::COMPRESS_BLOSC,
                                  openvdb::io::COMPRESS_ACTIVE_MASK,
                                  openvdb::io::COMPRESS_ACTIVE_MASK | openvdb::io::COMPRESS_ZIP,
                                  openvdb::io::COMPRESS_ACTIVE_MASK | openvdb::io::COMPRESS_BLOSC};
    const std::string path = tempPath("native.vdb");
    int checked = 0;
    for (openvdb::FloatGrid::Ptr grid : {sphere, fog})
        for (bool half : {false, true})
            for (uint32_t encoding : encodings)
                for (bool stream : {false, true}) {
                    grid->setSaveFloatAsHalf(half);
                    openvdb::GridPtrVec grids{vec, grid};
                    if (stream) {
                        std::ofstream out(path, std::ios::binary);
                        openvdb::io::Stream s(out);
                        s.setCompression(encoding);
                        s.write(grids);
                    } else {
                        openvdb::io::File f(path);
                        f.setCompression(encoding);
                        f.write(grids);
                    }
                    // What OpenVDB reads back (half precision is lossy, so compare with that).
                    openvdb::io::File in(path);
                    in.open();
                    auto ref =
                        openvdb::gridPtrCast<openvdb::FloatGrid>(in.readGrid(grid->getName()));
                    in.close();
                    const std::string what = grid->getName() + (half ? " half" : " full") +
                                             " encoding " + std::to_string(encoding) +
                                             (stream ? " stream" : " file");
                    if (stream) {
                        // Without grid offsets the Vec3 grid cannot be skipped: a clear error.
                        EXPECT_THROW(vdb::readVdbFile(path), InputError) << what;
                        continue;
                    }
                    const vdb::FloatGrid mine = vdb::readVdbFile(path);
                    // Every leaf decoded once, looked up where the tree locates a voxel.
                    std::vector<float> leaves(mine.tree.leaves.size() * vdb::kLeafVoxels);
                    vdb::LeafDecoder decoder(mine);
                    for (size_t l = 0; l < mine.tree.leaves.size(); ++l)
                        decoder.decode(l, leaves.data() + l * vdb::kLeafVoxels);
                    auto value = [&](int32_t x, int32_t y, int32_t z) {
                        const vdb::Location at = mine.tree.locate(x, y, z);
                        return at.leaf < 0
                                   ? at.value
                                   : leaves[static_cast<size_t>(at.leaf) * vdb::kLeafVoxels +
                                            static_cast<size_t>(at.voxel)];
                    };
                    EXPECT_EQ(mine.name, grid->getName()) << what;
                    EXPECT_EQ(mine.tree.background, ref->background()) << what;
                    auto acc = ref->getConstAccessor();
                    for (int i = 0; i < 20000; ++i) {
                        const Vec3 p = rng.inCube(300.0f);
                        const openvdb::Coord c(int(p.x), int(p.y), int(p.z));
                        ASSERT_EQ(value(c.x(), c.y(), c.z()), acc.getValue(c))
                            << what << " at " << c;
                    }
                    for (auto it = ref->tree().cbeginValueOn(); it; ++it)
                        ASSERT_EQ(value(it.getCoord().x(), it.getCoord().y(), it.getCoord().z()),
                                  *it)
                            << what;
                    if (grid == sphere)
                        for (int B : {4, 8}) {
                            const VdbImportOptions o{.blockSize = B};
                            expectSameGrid(loadVdb(path, o), importThroughOpenVdb(*ref, o),
                                           what + " B=" + std::to_string(B));
                        }
                    ++checked;
                }
    EXPECT_EQ(checked, 2 * 2 * 6);
    // A stream with the float grid first reads fine.
    std::ofstream out(path, std::ios::binary);
    openvdb::io::Stream(out).write({sphere});
    out.close();
    EXPECT_NO_THROW(loadVdb(path));
    std::filesystem::remove(path);
}

// The importer decodes the leaves as it gathers the blocks, each worker keeping a few: a level set
// of thousands of leaves imports to the same grid whether a worker keeps one tile's leaves (every
// tile evicts) or the default.
TEST(Vdb, StreamsItsLeavesIntoTheSameGrid) {
    openvdb::initialize();
    auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        1.0f, openvdb::Vec3f(0.1f, 0.2f, -0.3f), 0.0125f, 3.0f);
    const std::string path = tempPath("streamed.vdb");
    openvdb::io::File(path).write({sphere});
    EXPECT_GT(sphere->tree().leafCount(), 2000u);  // 216 (B = 4) or 1000 (8) fit a worker
    for (int B : {4, 8}) {
        const Grid reference = importThroughOpenVdb(*sphere, VdbImportOptions{.blockSize = B});
        for (size_t cached : {size_t{1}, size_t{0}})
            expectSameGrid(loadVdb(path, {.blockSize = B, .cachedLeaves = cached}), reference,
                           "B=" + std::to_string(B) + " cached " + std::to_string(cached));
    }
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace sdft
