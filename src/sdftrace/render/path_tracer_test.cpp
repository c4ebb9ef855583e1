#include "sdftrace/render/path_tracer.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sdftrace/render/temporal.h"
#include "sdftrace/scene/plan_render.h"
#include "test_scenes/shadow_test_scenes.h"

namespace sdft {
namespace {

// The shadow scene, all diffuse (no specular lobe, no ambient: the path tracer has neither).
std::string diffuseScene(const std::string& render) {
    std::string s = testing::shadowScene(testing::kSphereLight, render);
    const std::string ambient = R"("ambient": [0.1, 0.1, 0.1],)";
    s.replace(s.find(ambient), ambient.size(),
              R"("ambient": [0, 0, 0], "materials": {"default": {"specular": 0}},)");
    return s;
}

Film renderScene(Scene scene) {
    Film film(scene.camera.width, scene.camera.height);
    render(planRender(scene), film);
    return film;
}

// Means of b x b blocks (the path tracer integrates over the pixel, the direct integrator samples
// its centre: blocks average that difference away along edges).
std::vector<double> blockMeans(const Film& f, int b) {
    std::vector<double> out;
    for (int by = 0; by + b <= f.height; by += b)
        for (int bx = 0; bx + b <= f.width; bx += b) {
            double sum = 0;
            for (int y = by; y < by + b; ++y)
                for (int x = bx; x < bx + b; ++x)
                    for (int c = 0; c < 3; ++c) sum += f.color[3 * (size_t(y) * f.width + x) + c];
            out.push_back(sum / (3.0 * b * b));
        }
    return out;
}

// The diffuse scene at 80 x 48, as 8 x 8 block means.
std::vector<double> diffuseBlocks(const std::string& render) {
    Scene scene = parseSceneText(diffuseScene(render), "<test>");
    scene.camera.width = 80;
    scene.camera.height = 48;
    return blockMeans(renderScene(scene), 8);
}

// With one scattering event the path tracer estimates direct light: its mean is the direct
// integrator's image with distributed (ground-truth) shadows. Tolerance: the image means agree
// to 2 %, and 8 x 8 block means to 0.01 (about 4 % of the lit floor's radiance of 0.25) RMS.
TEST(PathTracer, MaxDepthOneConvergesToTheDirectIntegrator) {
    const std::vector<double> a =
        diffuseBlocks(R"({"shadow_method": "distributed", "shadow_rays": 256})");
    const std::vector<double> b =
        diffuseBlocks(R"({"integrator": "path", "spp": 256, "max_depth": 1})");
    double meanA = 0, meanB = 0, sq = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        meanA += a[i] / a.size();
        meanB += b[i] / b.size();
        sq += (a[i] - b[i]) * (a[i] - b[i]) / a.size();
    }
    EXPECT_GT(meanA, 0.05);
    EXPECT_NEAR(meanB, meanA, 0.02 * meanA);
    EXPECT_LT(std::sqrt(sq), 0.01);
}

// More bounces add light (the floor lights the boxes' sides and the shadows), never remove it.
TEST(PathTracer, IndirectLightAddsToDirect) {
    const std::vector<double> a =
        diffuseBlocks(R"({"integrator": "path", "spp": 32, "max_depth": 1})");
    const std::vector<double> b =
        diffuseBlocks(R"({"integrator": "path", "spp": 32, "max_depth": 8})");
    double sumA = 0, sumB = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        sumA += a[i];
        sumB += b[i];
        EXPECT_GT(b[i], a[i] * 0.95 - 1e-3) << i;
    }
    EXPECT_GT(sumB, sumA * 1.02);  // measured: +4 %
}

std::string furnace(const std::string& material) {
    return R"({"camera": {"eye": [0, 0, 4], "target": [0, 0, 0], "fov": 35, "width": 48,
                          "height": 48},
      "background": [0.5, 0.6, 0.7], "environment": [0.5, 0.6, 0.7], "ambient": [0, 0, 0],
      "materials": {"m": )" +
           material + R"(},
      "objects": [{"type": "sphere", "radius": 1, "material": "m"}],
      "render": {"integrator": "path", "spp": 64, "max_depth": 16}})";
}

// The furnace test: a convex object in a uniform environment without lights returns the
// environment times its albedo. Lossless glass and a white mirror return it exactly (every path
// escapes with weight 1); Lambertian albedo a returns a exactly (cosine sampling, one bounce);
// the glossy coat over a diffuse base reflects no more than it receives and loses little.
TEST(PathTracer, FurnaceConservesEnergy) {
    const Vec3 env(0.5f, 0.6f, 0.7f);
    struct Case {
        const char* material;
        float lo, hi;  // bounds on radiance / (environment x tint)
    };
    for (const Case& c :
         {Case{R"({"type": "dielectric", "ior": 1.5})", 0.995f, 1.005f},
          Case{R"({"type": "mirror", "color": [1, 1, 1]})", 0.995f, 1.005f},
          Case{R"({"color": [0.5, 0.5, 0.5], "specular": 0})", 0.495f, 0.505f},
          Case{R"({"color": [1, 1, 1], "specular": 1, "roughness": 0.3})", 0.85f, 1.02f}}) {
        SCOPED_TRACE(c.material);
        const testing::Rendered r = testing::renderText(furnace(c.material));
        const Film& f = r.film;
        double sum = 0;
        int n = 0;
        for (int y = 1; y + 1 < f.height; ++y)
            for (int x = 1; x + 1 < f.width; ++x) {
                // Inner pixels only: all samples of an edge pixel need not hit.
                bool inner = true;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx)
                        inner = inner && std::isfinite(f.depth[size_t(y + dy) * f.width + x + dx]);
                if (!inner) continue;
                const size_t i = size_t(y) * f.width + x;
                for (int k = 0; k < 3; ++k) sum += f.color[3 * i + k] / env[k];
                n += 3;
            }
        ASSERT_GT(n, 3 * 600);
        EXPECT_GE(sum / n, c.lo);
        EXPECT_LE(sum / n, c.hi);
    }
}

// Progressive rendering: frames of a few paths each average to the image of many paths (the
// error against a 512-path reference falls like 1/sqrt(paths)).
TEST(PathTracer, FramesAccumulateProgressively) {
    Scene scene = parseSceneText(
        diffuseScene(R"({"integrator": "path", "spp": 4, "max_depth": 3})"), "<test>");
    scene.camera.width = 40;
    scene.camera.height = 24;
    Scene refScene = scene;
    refScene.settings.samplesPerPixel = 512;
    const Film ref = renderScene(refScene);
    auto rmse = [&](const Film& f) {
        double sq = 0;
        for (size_t i = 0; i < f.color.size(); ++i)
            sq += (f.color[i] - ref.color[i]) * (f.color[i] - ref.color[i]);
        return std::sqrt(sq / f.color.size());
    };
    Film one(40, 24), sixteen(40, 24);
    render(planRender(scene), one);
    TemporalOptions o;
    o.frames = 16;
    o.jitterCamera = false;
    renderFrames(planRender(scene), sixteen, o, {}, false);
    // 16 times the paths: a quarter of the error in expectation; allow 0.4.
    EXPECT_LT(rmse(sixteen), 0.4 * rmse(one));
    EXPECT_GT(rmse(one), 0.0);
}

TEST(PathTracer, EveryMaterialAndLightGivesFinitePixels) {
    Scene scene = parseSceneFile(std::string(SDFT_SOURCE_DIR) + "/examples/path.json");
    scene.camera.width = 48;
    scene.camera.height = 30;
    scene.settings.samplesPerPixel = 4;
    for (const char* light :
         {testing::kSphereLight,
          R"({"type": "rect", "position": [-1, 4, 1], "u": [1, 0, 0], "v": [0, 0, 0.5]})",
          R"({"type": "directional", "direction": [0.6, -1, 0.5], "angle": 2})",
          R"({"type": "point", "position": [-2.5, 5, 1.5]})"}) {
        SCOPED_TRACE(light);
        Scene s = scene;
        s.lighting.lights =
            parseSceneText(testing::shadowScene(light, "{}"), "<test>").lighting.lights;
        Film film(48, 30);
        const RenderStats st = render(planRender(s), film);
        for (float c : film.color) ASSERT_TRUE(std::isfinite(c) && c >= 0);
        EXPECT_EQ(st.primaryRays, 48u * 30u * 4u);
        EXPECT_GT(st.secondaryRays, st.primaryRays / 2);
        EXPECT_GT(st.shadowRays, st.primaryRays / 2);
    }
}

}  // namespace
}  // namespace sdft
