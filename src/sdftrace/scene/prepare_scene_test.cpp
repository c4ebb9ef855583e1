#include "sdftrace/scene/prepare_scene.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "sdftrace/core/error.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/io/sdfg_io.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"

namespace sdft {
namespace {

namespace fs = std::filesystem;

const std::string kMeshes = std::string(SDFT_SOURCE_DIR) + "/data/meshes/";

// A small sphere grid file in a fresh directory.
struct GridDir {
    fs::path dir;
    GridDir() {
        dir = fs::temp_directory_path() / ("sdft_prepare_" + std::to_string(::getpid()));
        fs::create_directories(dir);
        const Tape tape = compileTape(node::sphere(0.5f), {.boundsCulling = false});
        SampleOptions o;
        o.resolution = 16;
        saveSdfg(sampleGrid(tape, tape.bounds(), o), (dir / "ball.sdfg").string());
    }
    ~GridDir() { fs::remove_all(dir); }
};

TEST(PrepareScene, DescribingReadsNoAssetAndPreparingLoadsEachOnce) {
    GridDir g;
    // The same grid file twice, the same mesh twice with the same options, once with others.
    const std::string text = R"({"objects": [
        {"grid": "ball.sdfg"},
        {"type": "grid", "file": "ball.sdfg", "translate": [2, 0, 0]},
        {"mesh": ")" + kMeshes +
                             R"(teapot.obj", "resolution": 16, "translate": [0, 2, 0]},
        {"mesh": ")" + kMeshes +
                             R"(teapot.obj", "resolution": 16, "translate": [0, 4, 0]},
        {"mesh": ")" + kMeshes +
                             R"(teapot.obj", "resolution": 20, "translate": [0, 6, 0]}]})";
    Scene scene = describeSceneText(text, "t.json", g.dir.string());
    EXPECT_FALSE(scene.prepared());
    ASSERT_EQ(scene.assets.size(), 3u);  // one grid file, two mesh bakes
    AssetCache cache;
    const PrepareStats first = prepareScene(scene, cache);
    EXPECT_TRUE(scene.prepared());
    EXPECT_EQ(first.loaded, 1u);
    EXPECT_EQ(first.baked, 2u);
    EXPECT_EQ(scene.root->children.size(), 5u);
    // The two references to one file share one grid.
    const Node* a = scene.root->children[0].get();
    const Node* b = scene.root->children[1]->children[0].get();
    ASSERT_EQ(a->kind, NodeKind::Grid);
    ASSERT_EQ(b->kind, NodeKind::Grid);
    EXPECT_EQ(a->grid, b->grid);
    // A second scene with the same assets is served by the cache.
    Scene again = describeSceneText(text, "t.json", g.dir.string());
    const PrepareStats second = prepareScene(again, cache);
    EXPECT_EQ(second.cached, 3u);
    EXPECT_EQ(second.loaded + second.baked, 0u);
    // The prepared scene plans and evaluates like the ball it holds (within a voxel of its
    // distance near the surface; the narrow band clamps the inside).
    const RenderPlan plan = planRender(scene);
    EXPECT_NEAR(plan.tape.eval({0.4f, 0, 0}), -0.1f, 0.05f);
    EXPECT_LT(plan.tape.eval({0, 0, 0}), 0.0f);
}

// The baker PrepareOptions names (render --device's GPU bakes) bakes every mesh asset, with the
// options the scene gives it, and its grid is the one the scene holds.
TEST(PrepareScene, MeshAssetsBakeThroughTheGivenBaker) {
    const std::string text = R"({"objects": [
        {"mesh": ")" + kMeshes +
                             R"(teapot.obj", "resolution": 16, "method": "jfa"},
        {"mesh": ")" + kMeshes +
                             R"(suzanne.obj", "resolution": 12, "translate": [3, 0, 0]}]})";
    Scene scene = describeSceneText(text, "t.json", kMeshes);
    std::vector<MeshBakeMethod> methods;
    std::vector<const Grid*> made;
    PrepareOptions o;
    o.bakeMesh = [&](const TriangleMesh& mesh, const MeshBakeOptions& bake) {
        methods.push_back(bake.method);
        MeshBakeResult r = bakeMesh(mesh, bake);
        r.grid = Grid::dense(r.grid.shape(), std::vector<float>(r.grid.shape().vertexCount(), -1));
        return r;
    };
    const PrepareStats stats = prepareScene(scene, o);
    EXPECT_EQ(stats.baked, 2u);
    ASSERT_EQ(methods.size(), 2u);
    EXPECT_EQ(methods[0], MeshBakeMethod::JumpFlood);
    EXPECT_EQ(methods[1], MeshBakeMethod::Exact);
    // The baker's grids (-1 everywhere) are what the prepared scene evaluates.
    EXPECT_EQ(planRender(scene).tape.eval({0, 0, 0}), -1.0f);
}

// Every narrow band a scene holds (a baked mesh, a grid file, a sampled subtree) gets its gap
// lattice, so that beyond the band it reads a bound of the surface's distance (decision 19); a
// dense one needs none.
TEST(PrepareScene, NarrowBandsInASceneGetTheirGapLattice) {
    GridDir d;
    const std::string text =
        R"({"objects": [
        {"mesh": ")" +
        kMeshes +
        R"(teapot.obj", "resolution": 24},
        {"mesh": ")" +
        kMeshes +
        R"(suzanne.obj", "resolution": 24, "dense": true, "translate": [3, 0, 0]},
        {"grid": "ball.sdfg", "translate": [-3, 0, 0]},
        {"type": "bake", "resolution": 24, "translate": [0, 3, 0],
         "child": {"type": "sphere", "radius": 0.5}}]})";
    for (bool lattice : {true, false}) {
        Scene scene = describeSceneText(text, "t.json", d.dir.string());
        PrepareOptions prepare;
        prepare.gapLattice = lattice;
        prepareScene(scene, prepare);
        const Tape tape = planRender(scene).tape;
        int sparse = 0, dense = 0;
        for (const auto& g : tape.grids()) {
            if (g->kind() == GridKind::Dense) {
                ++dense;
                EXPECT_EQ(g->view().gapLattice, nullptr);
                continue;
            }
            ++sparse;
            EXPECT_EQ(g->view().gapLattice != nullptr, lattice);
        }
        EXPECT_EQ(dense, 1);
        EXPECT_EQ(sparse, 3);
    }
}

TEST(PrepareScene, AMissingFileIsAnErrorOfPreparationWithItsJsonPath) {
    Scene scene = describeSceneText(R"({"objects": [{"type": "sphere", "radius": 1},
        {"type": "grid", "file": "nowhere.sdfg"}]})",
                                    "t.json", "/nonexistent-dir");
    EXPECT_EQ(scene.assets.size(), 1u);
    try {
        prepareScene(scene);
        FAIL() << "a missing grid file prepared";
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.rfind("t.json: /objects/1/file: ", 0), 0u) << m;
    }
}

// A "bake" of a subtree that holds a grid file: the file loads first, the subtree samples it.
TEST(PrepareScene, SubtreeBakesSeeTheirOwnGrids) {
    GridDir g;
    Scene scene = describeSceneText(R"({"objects": [{"type": "bake", "resolution": 24,
        "child": {"type": "union", "children": [{"grid": "ball.sdfg"},
                  {"type": "sphere", "radius": 0.3, "translate": [0.6, 0, 0]}]}}]})",
                                    "t.json", g.dir.string());
    ASSERT_EQ(scene.assets.size(), 2u);
    EXPECT_EQ(scene.assets[0].kind, AssetRequest::Kind::GridFile);
    EXPECT_EQ(scene.assets[1].kind, AssetRequest::Kind::Subtree);
    prepareScene(scene);
    const RenderPlan plan = planRender(scene);
    EXPECT_LT(plan.tape.eval({0, 0, 0}), 0.0f);      // inside the ball
    EXPECT_LT(plan.tape.eval({0.75f, 0, 0}), 0.0f);  // inside the small sphere
    EXPECT_GT(plan.tape.eval({0, 0.8f, 0}), 0.0f);
}

// The overlap of a repetition's copies is checked once its grid child is loaded.
TEST(PrepareScene, RepetitionsOfGridsAreCheckedOnceLoaded) {
    GridDir g;
    auto scene = [&](const char* cell) {
        return std::string(R"({"objects": [{"type": "repeat", "cell": )") + cell +
               R"(, "count": [2, 0, 0], "child": {"grid": "ball.sdfg"}}]})";
    };
    // The grid's bounds are its samples' (the ball, its band and padding: 1.33 from the origin).
    Scene ok = describeSceneText(scene("[2.7, 1, 1]"), "t.json", g.dir.string());
    EXPECT_EQ(ok.repeatChecks.size(), 1u);
    EXPECT_NO_THROW(prepareScene(ok));
    Scene overlapping = describeSceneText(scene("[2.5, 1, 1]"), "t.json", g.dir.string());
    try {
        prepareScene(overlapping);
        FAIL() << "overlapping copies prepared";
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("t.json: /objects/0/cell: "), std::string::npos) << m;
        EXPECT_NE(m.find("do not overlap"), std::string::npos) << m;
    }
}

}  // namespace
}  // namespace sdft
