#include "sdftrace/io/vdb_io.h"

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "sdftrace/core/error.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/test_util.h"
#include "sdftrace/io/grid_file.h"
#include "test_files.h"

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
    expectError(garbage, "cannot read OpenVDB file");
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
    for (const auto& p : {garbage, vec, stretched}) std::filesystem::remove(p);
}

}  // namespace
}  // namespace sdft
