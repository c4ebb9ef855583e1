#include "sdftrace/view/progressive_view.h"

#include <gtest/gtest.h>

#include "sdftrace/render/temporal.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"

namespace sdft {
namespace {

RenderPlan demoPlan(int w, int h) {
    Scene scene = demoScene();
    scene.camera.width = w;
    scene.camera.height = h;
    return planRender(scene);
}

TEST(ProgressiveView, APreviewComesFirstThenTheFramesOfRenderFrames) {
    const RenderPlan plan = demoPlan(64, 36);
    ProgressiveView view({.frames = 4, .previewDivisor = 4});
    view.setPlan(plan);
    view.setCamera(plan.camera);
    EXPECT_FALSE(view.done());
    view.step();
    EXPECT_TRUE(view.showingPreview());
    EXPECT_EQ(view.film().width, 16);
    EXPECT_EQ(view.film().height, 9);
    int passes = 0;
    while (!view.done()) {
        view.step();
        ++passes;
    }
    EXPECT_EQ(passes, 4);
    EXPECT_FALSE(view.showingPreview());
    // The same pixels as render --frames 4.
    Film reference(64, 36);
    renderFrames(plan, reference, TemporalOptions{.frames = 4});
    EXPECT_EQ(view.film().color, reference.color);
    EXPECT_EQ(view.film().depth, reference.depth);
}

TEST(ProgressiveView, OneFrameIsThePlainRender) {
    const RenderPlan plan = demoPlan(40, 30);
    ProgressiveView view({.frames = 1});
    view.setPlan(plan);
    while (!view.done()) view.step();
    Film reference(40, 30);
    render(plan, reference);
    EXPECT_EQ(view.film().color, reference.color);
}

TEST(ProgressiveView, AMovedCameraStartsOverWithAPreview) {
    const RenderPlan plan = demoPlan(48, 32);
    ProgressiveView view({.frames = 2});
    view.setPlan(plan);
    while (!view.done()) view.step();
    CameraDesc moved = plan.camera;
    moved.eye = moved.eye + Vec3(0.5f, 0, 0);
    view.setCamera(moved);
    EXPECT_FALSE(view.done());
    EXPECT_EQ(view.framesDone(), 0);
    view.step();
    EXPECT_TRUE(view.showingPreview());
    while (!view.done()) view.step();
    RenderPlan movedPlan = plan;
    movedPlan.camera = moved;
    Film reference(48, 32);
    renderFrames(movedPlan, reference, TemporalOptions{.frames = 2});
    EXPECT_EQ(view.film().color, reference.color);
}

}  // namespace
}  // namespace sdft
