// Whitted rays per pixel (whitted_pixel.h) as a device thread runs them, shadePixel: primary ray,
// normal and shadows one pixel at a time, on the CPU against the CPU renderer, which runs the same
// ray tree for its tiles' hits after packets of primary and shadow rays: the same secondary rays,
// their field evaluations, self-intersections and the shadow evaluations of primary and secondary
// hits (summed over the film) and the same colours to float rounding (1e-4 on colours of order 1).
#include "sdftrace/render/whitted_pixel.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "sdftrace/render/render_plan.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"

namespace sdft {
namespace {

struct Totals {
    uint64_t rays = 0, evaluations = 0, selfIntersections = 0, shadowEvaluations = 0;
    int specularPixels = 0;
};

// shadePixel over the film against render(): colours, and the secondary counters' totals.
Totals whittedLikeTheRenderer(const RenderPlan& plan) {
    const int w = plan.camera.width, h = plan.camera.height;
    FrameView frame;
    frame.camera = plan.camera;
    Film film(w, h);
    const RenderStats stats = render(plan, frame, film, false);
    const DirectPixelTables tables = directPixelTables(plan);
    const DirectPixelView view = directPixelView(plan, frame, tables, w);
    const WhittedPixelTables wt = whittedPixelTables(plan);
    const WhittedPixelView wv = whittedPixelView(plan, wt);
    const bool failedBefore = ::testing::Test::HasFailure();
    Totals t;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            const DirectPixel px = shadePixel<kTapeMaxScalarRegs, true>(view, wv, x, y);
            EXPECT_EQ(px.primary.trace.hit, std::isfinite(film.depth[i])) << x << "," << y;
            for (int a = 0; a < 3; ++a)
                EXPECT_NEAR(px.color[a], film.color[3 * i + a],
                            1e-4f * std::fmax(1.0f, film.color[3 * i + a]))
                    << x << "," << y;
            t.rays += px.secondaryRays;
            t.evaluations += px.secondaryEvaluations;
            t.selfIntersections += px.selfIntersections;
            t.shadowEvaluations += px.shadowEvaluations;
            t.specularPixels += px.primary.trace.hit && px.material.kind != Material::Kind::Plastic;
            if (!failedBefore && ::testing::Test::HasFailure()) return t;
        }
    }
    EXPECT_EQ(t.rays, stats.secondaryRays);
    EXPECT_EQ(t.evaluations, stats.secondaryEvaluations);
    EXPECT_EQ(t.selfIntersections, stats.selfIntersections);
    // The primary hits' shadow rays and the secondary hits' (whose evaluations count too).
    EXPECT_EQ(t.shadowEvaluations, stats.shadowEvaluations);
    return t;
}

Scene example(const char* name, int w, int h) {
    Scene scene = parseSceneFile(std::string(SDFT_SOURCE_DIR) + "/examples/" + name + ".json");
    scene.camera.width = w;
    scene.camera.height = h;
    scene.settings.threads = 1;
    return scene;
}

// Glass (refraction through convex bounds and through the interior, absorption, total internal
// reflection); Keinert's budgets and shallow ones, the global
// epsilon, soft and distributed shadows at secondary hits, a far camera.
TEST(WhittedPixel, MatchesTheRenderersWhittedRays) {
    uint64_t rays = 0;
    int specular = 0;
    for (const char* name : {"glass", "glass_shapes"}) {
        SCOPED_TRACE(name);
        const Scene original = example(name, 40, 24);
        for (int variant = 0; variant < 6; ++variant) {
            SCOPED_TRACE(variant);
            Scene scene = original;
            switch (variant) {
                case 1:
                    scene.settings.convexBounds = false;
                    break;
                case 2:
                    scene.settings.maxReflections = 1;
                    scene.settings.maxRefractions = 2;
                    scene.settings.dynamicEpsilon = false;
                    break;
                case 3:
                    scene.settings.shadowMethod = ShadowMethod::Soft;
                    break;
                case 4:
                    scene.settings.shadowMethod = ShadowMethod::Distributed;
                    scene.settings.shadowRays = 3;
                    break;
                case 5:
                    scene.camera.eye = original.camera.target +
                                       (original.camera.eye - original.camera.target) * 2.0f;
                    break;
            }
            const RenderPlan plan = planRender(scene);
            ASSERT_EQ(directPixelUnsupported(plan), "");
            ASSERT_TRUE(planHasWhitted(plan));
            const Totals t = whittedLikeTheRenderer(plan);
            rays += t.rays;
            specular += t.specularPixels;
        }
    }
    EXPECT_GT(specular, 1000);
    EXPECT_GT(rays, 20000u);
}

// Every material of the demo made a mirror: reflections of reflections until the budget.
TEST(WhittedPixel, MatchesTheRenderersMirrors) {
    Scene scene = example("demo", 48, 28);
    for (Material& m : scene.materials) {
        m.kind = Material::Kind::Mirror;
        m.color = Vec3(0.9f, 0.85f, 0.8f);
    }
    scene.settings.maxReflections = 3;
    const RenderPlan plan = planRender(scene);
    ASSERT_EQ(directPixelUnsupported(plan), "");
    const Totals t = whittedLikeTheRenderer(plan);
    EXPECT_GT(t.specularPixels, 500);
    EXPECT_GT(t.rays, static_cast<uint64_t>(t.specularPixels));  // second bounces happen
}

// Whitted rays that land on textured surfaces: the textures example's turbulence sphere a mirror
// and its noise torus glass, so reflected and refracted rays see the checker floor, the marble,
// the wood and the image-textured box.
TEST(WhittedPixel, SecondaryHitsOnTexturesMatchTheRenderer) {
    Scene scene = example("textures", 48, 28);
    int specular = 0;
    for (Material& m : scene.materials) {
        if (m.name == "turbulence") m.kind = Material::Kind::Mirror, ++specular;
        if (m.name == "noise") m.kind = Material::Kind::Dielectric, ++specular;
    }
    ASSERT_EQ(specular, 2);
    const RenderPlan plan = planRender(scene);
    ASSERT_EQ(directPixelUnsupported(plan), "");
    const Totals t = whittedLikeTheRenderer(plan);
    EXPECT_GT(t.specularPixels, 20);
    EXPECT_GT(t.rays, static_cast<uint64_t>(t.specularPixels));
}

// Budgets deeper than the stack stay on the CPU, named.
TEST(WhittedPixel, DeeperBudgetsThanTheStackAreNamed) {
    Scene scene = example("glass", 16, 9);
    scene.settings.maxRefractions = kWhittedMaxBounces;
    scene.settings.maxReflections = 1;
    EXPECT_NE(directPixelUnsupported(planRender(scene)).find("Whitted budgets above"),
              std::string::npos);
    scene.settings.maxReflections = 0;
    EXPECT_EQ(directPixelUnsupported(planRender(scene)), "");
}

}  // namespace
}  // namespace sdft
