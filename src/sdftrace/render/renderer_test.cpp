#include "sdftrace/render/renderer.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sdftrace/core/error.h"
#include "sdftrace/field/test_util.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"
#include "sdftrace/scene/render_options.h"
#include "test_scenes/shadow_test_scenes.h"

namespace sdft {
namespace {

TEST(Normals, BothEstimatorsMatchAnalyticNormals) {
    Tape sphereTape = compileTape(node::sphere(1.0f));
    Tape torusTape = compileTape(node::torus(1.0f, 0.3f));
    testing::Rng rng(21);
    for (NormalEstimator e : {NormalEstimator::Central, NormalEstimator::Tetrahedral}) {
        for (int i = 0; i < 2000; ++i) {
            Vec3 u = rng.direction();
            Vec3 n = estimateNormal(sphereTape, u * 1.0005f, 1e-3f, e);
            EXPECT_GT(dot(n, u), 0.99999f);
            // Torus: the normal points from the ring's core circle to the point.
            float a = rng.uniform(0, 6.2831853f), b = rng.uniform(0, 6.2831853f);
            Vec3 core(std::cos(a), 0, std::sin(a));
            Vec3 dir = core * std::cos(b) + Vec3(0, std::sin(b), 0);
            Vec3 p = core + dir * 0.3f;
            EXPECT_GT(dot(estimateNormal(torusTape, p, 1e-3f, e), dir), 0.9999f);
        }
    }
}

TEST(Renderer, DemoHasNoNonFinitePixelAndCountsEveryRay) {
    Scene scene = demoScene();
    scene.camera.width = 96;
    scene.camera.height = 54;
    scene.settings.threads = 1;
    Film film(96, 54);
    RenderStats stats = render(planRender(scene), film);
    EXPECT_EQ(stats.threads, 1);
    EXPECT_EQ(stats.primaryRays, 96u * 54u);
    EXPECT_GT(stats.hits, stats.primaryRays / 2);
    double steps = 0;
    for (size_t i = 0; i < film.pixels(); ++i) {
        for (int c = 0; c < 3; ++c) {
            ASSERT_TRUE(std::isfinite(film.color[3 * i + c])) << i;
            ASSERT_TRUE(std::isfinite(film.normal[3 * i + c])) << i;
        }
        ASSERT_FALSE(std::isnan(film.depth[i])) << i;
        ASSERT_TRUE(std::isfinite(film.error[i])) << i;
        steps += film.steps[i];
    }
    // The steps AOV is the per-pixel count of the primary-ray evaluations in the stats.
    EXPECT_EQ(steps, static_cast<double>(stats.primaryEvaluations));
}

// A plan whose grid's values live on the GPU (render --device cuda's RTSDF frames) holds only a
// stand-in on the host: the CPU renderer refuses it with one line rather than rendering stale
// values.
TEST(Renderer, RefusesAPlanWhoseGridLivesOnTheGpu) {
    Scene scene = demoScene();
    scene.camera.width = 8;
    scene.camera.height = 8;
    RenderPlan plan = planRender(scene);
    GridShape shape;
    shape.cells[0] = shape.cells[1] = shape.cells[2] = 1;
    const Grid stand = Grid::dense(shape, std::vector<float>(8, 1.0f));
    plan.deviceGrids.push_back({&stand, nullptr});
    Film film(8, 8);
    try {
        render(plan, film);
        ADD_FAILURE() << "the CPU rendered a plan with a device-resident grid";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("--device cuda"), std::string::npos) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
    EXPECT_THROW(FrameRenderer(plan, FrameView{plan.camera}, film), InputError);
}

// Primary rays reach past the scene from a camera far away: t_max is raised to the scene's far
// side unless max_distance is given (a sphere 300 units off was black under the former fixed
// t_max of 100, and so was a grid file seen with --eye past 4 times its framing distance).
TEST(Renderer, AFarCameraStillSeesTheScene) {
    const char* far = R"({"camera": {"eye": [0, 0, 300], "target": [0, 0, 0], "fov": 2,
                                     "width": 16, "height": 16},
                          "objects": [{"type": "sphere", "radius": 2}]})";
    const RenderPlan autoPlan = planRender(parseSceneText(far, "far.json"));
    EXPECT_GE(autoPlan.settings.maxDistance, 302.0f);
    Film film(16, 16);
    EXPECT_GT(render(autoPlan, film).hits, 0u);
    Scene clipped = parseSceneText(far, "far.json");
    ASSERT_TRUE(findRenderOption("max_distance"));
    findRenderOption("max_distance")->set(clipped.settings, 100);
    const RenderPlan clippedPlan = planRender(clipped);
    EXPECT_EQ(clippedPlan.settings.maxDistance, 100.0f);
    EXPECT_EQ(render(clippedPlan, film).hits, 0u);
    // The reach is the same from every eye at the camera's distance from its target (orbits),
    // and covers every corner of the bounds from there.
    const Bounds3 b{Vec3(-1, -2, -3), Vec3(4, 5, 6)};
    CameraDesc cam;
    cam.target = Vec3(1, 1, 1);
    cam.eye = cam.target + Vec3(0, 0, 150);
    const float reach = resolveMaxDistance(RenderSettings{}, cam, b);
    for (const Vec3 dir : {Vec3(1, 0, 0), Vec3(0, -1, 0), normalize(Vec3(1, 1, -1))}) {
        cam.eye = cam.target + dir * 150.0f;
        EXPECT_EQ(resolveMaxDistance(RenderSettings{}, cam, b), reach);
        for (int c = 0; c < 8; ++c) {
            const Vec3 p((c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y,
                         (c & 4) ? b.hi.z : b.lo.z);
            EXPECT_GE(reach, length(p - cam.eye));
        }
    }
    EXPECT_EQ(resolveMaxDistance(RenderSettings{}, cam, Bounds3::everything()), 100.0f);
}

// Lengths the user did not give (shadow offset, AO step, tau, the normals' spacing, ...) scale
// down with a scene smaller than a unit (sceneLengthFactor): the same scene at a thousandth of the
// size renders the same image (measured: mean difference 2.5e-7). With the fixed defaults the
// shadow rays of the small scene's floor started above its sphere, the AO samples far outside it
// and the normals' spacing was half its torus's tube (mean difference 0.49). Soft shadows too:
// their marches towards the sun run on to max_distance, ten thousand times the small scene's size
// (triangulation's estimate once fell to 0 there: mean difference 0.31).
TEST(Renderer, ASceneSmallerThanAUnitRendersAsAtUnitScale) {
    auto scene = [](float s, const char* shadows = "hard") {
        char text[900];
        std::snprintf(text, sizeof text, R"({
          "camera": {"eye": [0, %g, %g], "target": [0, 0, 0], "width": 48, "height": 32},
          "lights": [{"type": "directional", "direction": [-0.4, -1, -0.5], "intensity": 2,
                      "angle": 3}],
          "objects": [{"type": "box", "size": [%g, %g, %g], "translate": [0, %g, 0]},
                      {"type": "sphere", "radius": %g},
                      {"type": "torus", "major_radius": %g, "minor_radius": %g,
                       "translate": [%g, 0, 0]}],
          "render": {"shadow_method": "%s", "ao": true}})",
                      1 * s, 4 * s, 6 * s, 0.1 * s, 6 * s, -1.05 * s, 1 * s, 0.8 * s, 0.2 * s,
                      1.5 * s, shadows);
        return parseSceneText(text, "scaled.json");
    };
    // 0.85 and 0.00085 units across: defaults at 0.85 and 0.00085 times theirs.
    const RenderPlan unit = planRender(scene(0.1f)), small = planRender(scene(0.0001f));
    EXPECT_FLOAT_EQ(unit.settings.shadowOffsetMin,
                    RenderSettings{}.shadowOffsetMin * length(unit.sceneBounds.extent()));
    EXPECT_FLOAT_EQ(small.settings.ao.step,
                    RenderSettings{}.ao.step * length(small.sceneBounds.extent()));
    EXPECT_EQ(planRender(scene(1)).settings.shadowOffsetMin, RenderSettings{}.shadowOffsetMin);
    Film a(48, 32), b(48, 32);
    render(unit, a);
    render(small, b);
    double diff = 0;
    for (size_t i = 0; i < a.color.size(); ++i) diff += std::fabs(a.color[i] - b.color[i]);
    EXPECT_LT(diff / static_cast<double>(a.color.size()), 1e-4);
    render(planRender(scene(0.1f, "soft")), a);
    render(planRender(scene(0.0001f, "soft")), b);
    diff = 0;
    for (size_t i = 0; i < a.color.size(); ++i) diff += std::fabs(a.color[i] - b.color[i]);
    EXPECT_LT(diff / static_cast<double>(a.color.size()), 1e-3) << "soft shadows";
    // A given length is kept.
    Scene given = scene(0.0001f);
    findRenderOption("shadow_offset")->give(given.settings, 0.01);
    EXPECT_FLOAT_EQ(planRender(given).settings.shadowOffsetMin, 0.01f);
}

TEST(Renderer, ThreadCountDoesNotChangeTheImage) {
    Scene scene = demoScene();
    scene.camera.width = 64;
    scene.camera.height = 40;
    Film one(64, 40), two(64, 40);
    scene.settings.threads = 1;
    render(planRender(scene), one);
    scene.settings.threads = 2;
    EXPECT_EQ(render(planRender(scene), two).threads, 2);
    EXPECT_EQ(one.color, two.color);
    EXPECT_EQ(one.depth, two.depth);
}

// A frame split into tiles, each group rendered by its own FrameRenderer into its own film (as the
// ranks of a distributed render do), is the whole frame's image bit for bit: direct lighting with
// shadows, and the path tracer.
TEST(Renderer, TilesRenderedApartMakeTheSameImage) {
    for (const std::string file : {"", "/examples/path.json", "/examples/jewel.json"}) {
        SCOPED_TRACE(file);
        Scene scene =
            file.empty() ? demoScene() : parseSceneFile(std::string(SDFT_SOURCE_DIR) + file);
        scene.camera.width = 70;  // tiles cut by the film's edges
        scene.camera.height = 37;
        scene.settings.samplesPerPixel = 2;
        const RenderPlan plan = planRender(scene);
        Film whole(70, 37);
        const RenderStats all = render(plan, whole);
        Film pieced(70, 37);
        FrameView view{plan.camera};
        RenderStats sum;
        const int tiles = FrameRenderer(plan, view, pieced).tileCount();
        ASSERT_GT(tiles, 6);
        for (int last = tiles; last > 0; last -= 5) {  // back to front, 5 at a time
            const int first = std::max(0, last - 5);
            Film part(70, 37);
            FrameRenderer frame(plan, view, part);
            frame.renderTiles(first, last);
            sum.add(frame.stats());
            for (int t = first; t < last; ++t) {
                const PixelRect r = frame.tile(t);
                for (int y = r.y0; y < r.y1; ++y)
                    for (int x = r.x0; x < r.x1; ++x) {
                        const size_t p = static_cast<size_t>(y) * 70 + x;
                        for (int c = 0; c < 3; ++c) pieced.color[3 * p + c] = part.color[3 * p + c];
                        pieced.depth[p] = part.depth[p];
                        pieced.steps[p] = part.steps[p];
                    }
            }
        }
        EXPECT_EQ(whole.color, pieced.color);
        EXPECT_EQ(whole.depth, pieced.depth);
        EXPECT_EQ(whole.steps, pieced.steps);
        EXPECT_EQ(all.primaryRays, sum.primaryRays);
        EXPECT_EQ(all.primaryEvaluations, sum.primaryEvaluations);
    }
}

// Every shadow method, with ambient occlusion, on sphere, rectangle, sun and point lights: no NaN
// or infinite pixel, and the shadow and ao AOVs stay in [0, 1].
TEST(Renderer, EveryShadowMethodGivesFinitePixels) {
    for (const char* light :
         {testing::kSphereLight,
          R"({"type": "rect", "position": [-1, 4, 1], "u": [1, 0, 0], "v": [0, 0, 0.5]})",
          R"({"type": "directional", "direction": [0.6, -1, 0.5], "angle": 2})",
          R"({"type": "point", "position": [-2.5, 5, 1.5]})"}) {
        for (const char* method : {"hard", "soft", "distributed", "pcf", "evsm"}) {
            const testing::Rendered r = testing::renderText(testing::shadowScene(
                light, std::string(R"({"shadow_method": ")") + method +
                           R"(", "shadow_rays": 16, "shadow_map_resolution": 128, "ao": true})"));
            for (float c : r.film.color) ASSERT_TRUE(std::isfinite(c)) << light << " " << method;
            for (size_t i = 0; i < r.film.pixels(); ++i) {
                ASSERT_TRUE(r.film.shadow[i] >= 0 && r.film.shadow[i] <= 1) << method;
                ASSERT_TRUE(r.film.ao[i] >= 0 && r.film.ao[i] <= 1) << method;
            }
            EXPECT_GT(r.stats.shadowEvaluations, 0u) << light << " " << method;
            EXPECT_GT(r.stats.aoEvaluations, 0u);
        }
    }
}

// Mirrors and glass under every shadow method (secondary hits are shaded with it): finite pixels.
TEST(Renderer, WhittedScenesGiveFinitePixels) {
    Scene base = parseSceneFile(std::string(SDFT_SOURCE_DIR) + "/examples/glass.json");
    for (ShadowMethod m : {ShadowMethod::Hard, ShadowMethod::Soft, ShadowMethod::Distributed,
                           ShadowMethod::Pcf, ShadowMethod::Evsm}) {
        Scene scene = base;
        scene.camera.width = 64;
        scene.camera.height = 40;
        scene.settings.shadowMethod = m;
        scene.settings.shadowRays = 4;
        scene.settings.shadowMap.resolution = 64;
        Film film(64, 40);
        const RenderStats st = render(planRender(scene), film);
        for (float c : film.color) ASSERT_TRUE(std::isfinite(c));
        EXPECT_GT(st.secondaryRays, 100u);
    }
}

}  // namespace
}  // namespace sdft
