#include "sdftrace/render/primary_pixel.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "sdftrace/render/primary_test_scenes.h"
#include "sdftrace/render/render_plan.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"

namespace sdft {
namespace {

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
            if (!primaryPixelUnsupported(plan).empty()) break;
            if (variant == 0) ++scenes;
            Film film(72, 40);
            render(plan, film);
            FrameView frame;
            frame.camera = plan.camera;
            const PrimaryPixelView view = primaryPixelView(plan, frame);
            int hits = 0;
            for (int y = 0; y < 40; ++y) {
                for (int x = 0; x < 72; ++x) {
                    const size_t i = static_cast<size_t>(y) * 72 + x;
                    const PrimaryPixel px = tracePrimaryPixel(view, x, y);
                    ASSERT_EQ(px.trace.hit, std::isfinite(film.depth[i])) << x << "," << y;
                    ASSERT_EQ(px.trace.evaluations, film.steps[i]) << x << "," << y;
                    if (!px.trace.hit) continue;
                    ++hits;
                    ASSERT_EQ(px.trace.t, film.depth[i]) << x << "," << y;
                    for (int a = 0; a < 3; ++a)
                        ASSERT_NEAR(px.normal[a], film.normal[3 * i + a], 1e-5f) << x << "," << y;
                }
            }
            EXPECT_GT(hits, 0);
        }
    }
    EXPECT_EQ(scenes, static_cast<int>(testing::kPrimaryTestScenes.size()));
}

}  // namespace
}  // namespace sdft
