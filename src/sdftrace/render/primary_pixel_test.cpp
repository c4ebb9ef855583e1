#include "sdftrace/render/primary_pixel.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "sdftrace/render/render_plan.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"
#include "test_scenes/grid_test_scenes.h"
#include "test_scenes/primary_test_scenes.h"

namespace sdft {
namespace {

// Renders `plan` with the CPU renderer and holds tracePrimaryPixel to its film; the hits.
int matchesTheRenderer(const RenderPlan& plan) {
    const int w = plan.camera.width, h = plan.camera.height;
    Film film(w, h);
    render(plan, film);
    FrameView frame;
    frame.camera = plan.camera;
    PrimaryPixelView view = primaryPixelView(plan, frame);
    const MinMaxBuffer minMax = primaryMinMax(plan, view.camera);  // Jamriška §6, as render() has
    view.minMax = minMax.view();
    const bool failedBefore = ::testing::Test::HasFailure();  // report this plan's first
    int hits = 0;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            const PrimaryPixel px = tracePrimaryPixel(view, x, y);
            EXPECT_EQ(px.trace.hit, std::isfinite(film.depth[i])) << x << "," << y;
            EXPECT_EQ(px.trace.evaluations, film.steps[i]) << x << "," << y;
            if (plan.ddaGrid && !plan.settings.shadows) {  // shadow rays add to these
                EXPECT_EQ(px.traversalSteps, film.travSteps[i]) << x << "," << y;
                EXPECT_EQ(px.intersectionTests, film.isectTests[i]) << x << "," << y;
            }
            if (!failedBefore && ::testing::Test::HasFailure()) return hits;
            if (!px.trace.hit) continue;
            ++hits;
            EXPECT_EQ(px.trace.t, film.depth[i]) << x << "," << y;
            for (int a = 0; a < 3; ++a)
                EXPECT_NEAR(px.normal[a], film.normal[3 * i + a], 1e-5f) << x << "," << y;
        }
    }
    return hits;
}

// The device path's per-pixel function, run here on the CPU, against the CPU renderer's tiles of
// packets: the same hits, depths, evaluation counts and normals on every example scene it
// supports (analytic scenes, CSG, blends, displacement, repetition, baked meshes as grids in the
// tape), at a close and a far camera, with and without the enhancements. The batch evaluator
// rounds as the scalar one does, so they agree exactly; normals within float rounding. (The path
// tracer samples its primary rays per sample: not this renderer's.)
TEST(PrimaryPixel, MatchesTheRenderersPrimaryRaysOnTheExamples) {
    int scenes = 0;
    for (const char* name : testing::kPrimaryTestScenes) {
        SCOPED_TRACE(name);
        Scene scene = parseSceneFile(std::string(SDFT_SOURCE_DIR) + "/examples/" + name + ".json");
        scene.camera.width = 72;
        scene.camera.height = 40;
        scene.settings.threads = 1;
        const CameraDesc original = scene.camera;
        for (int variant = 0; variant < 3; ++variant) {
            SCOPED_TRACE(variant);
            scene.camera = original;
            if (variant == 1) {  // far: the eye twice as far from the target
                scene.camera.eye = original.target + (original.eye - original.target) * 2.0f;
            }
            if (variant == 2) scene.settings.trace = TraceOptions::classic();
            const RenderPlan plan = planRender(scene);
            if (variant == 0) ++scenes;
            EXPECT_GT(matchesTheRenderer(plan), 0);
        }
    }
    EXPECT_EQ(scenes, static_cast<int>(testing::kPrimaryTestScenes.size()));
}

// Lone grids by Jamriška's DDA (§4): the same hits, depths, reconstruction counts, traversal
// counters and §5 normals as the renderer's DDA, sparse (4- and 8-blocks) and dense, with false
// position and midpoint cell hits, bit masks on and off, the three gradient estimators, and rays
// narrowed by §6's min/max buffer (64 and 128 pixels, a near camera whose blocks may reach the
// camera plane).
TEST(PrimaryPixel, MatchesTheRenderersGridDdaOnLoneGrids) {
    for (auto& [name, original] : testing::ddaTestScenes(64, 36)) {
        SCOPED_TRACE(name);
        for (int variant = 0; variant < 6; ++variant) {
            SCOPED_TRACE(variant);
            Scene scene = original;
            scene.settings.threads = 1;
            scene.settings.shadows = false;
            if (variant == 4) scene.settings.minMaxResolution = 64;
            if (variant == 5) {  // near
                scene.settings.minMaxResolution = 128;
                scene.camera.eye =
                    original.camera.target + (original.camera.eye - original.camera.target) * 0.6f;
            }
            if (variant == 1) {
                scene.settings.gridTrace.cellMethod = CellIntersection::Midpoint;
                scene.settings.gridNormals = GridNormal::AnalyticTrilinear;
            }
            if (variant == 2) {
                scene.settings.gridTrace.bitMasks = false;
                scene.settings.gridTrace.falsiIters = 3;
                scene.settings.gridNormals = GridNormal::DifferenceOfInterpolations;
            }
            if (variant == 3)  // far
                scene.camera.eye =
                    original.camera.target + (original.camera.eye - original.camera.target) * 2.0f;
            const RenderPlan plan = planRender(scene);
            ASSERT_TRUE(plan.ddaGrid);
            EXPECT_GT(matchesTheRenderer(plan), 40);
            // A sparse grid's buffer narrows: some pixels' rays are not traced at all (a dense
            // grid is one block, one square over its whole image).
            if (variant == 4 && name.find("sparse") != std::string::npos) {
                const MinMaxBuffer b = primaryMinMax(plan, Camera(plan.camera));
                int empty = 0;
                for (int y = 0; y < plan.camera.height; ++y)
                    for (int x = 0; x < plan.camera.width; ++x) {
                        float t0, t1;
                        b.range(x, y, t0, t1);
                        empty += t0 > t1;
                    }
                EXPECT_GT(empty, 100);
            }
        }
    }
}

}  // namespace
}  // namespace sdft
