#include <gtest/gtest.h>

#include <cmath>

#include "sdftrace/field/node.h"
#include "sdftrace/render/optics.h"
#include "test_scenes/shadow_test_scenes.h"

namespace sdft {
namespace {

TEST(Fresnel, NormalIncidenceGrazingAndTotalInternalReflection) {
    EXPECT_NEAR(fresnelDielectric(1.0f, 1.0f, 1.5f), 0.04f, 1e-6f);  // ((1 - 1.5) / 2.5)^2
    EXPECT_NEAR(fresnelDielectric(1.0f, 1.5f, 1.0f), 0.04f, 1e-6f);
    EXPECT_GT(fresnelDielectric(0.01f, 1.0f, 1.5f), 0.9f);
    // From glass, beyond the critical angle asin(1/1.5) ~ 41.8 degrees: all reflected.
    EXPECT_EQ(fresnelDielectric(std::cos(radians(45.0f)), 1.5f, 1.0f), 1.0f);
    EXPECT_LT(fresnelDielectric(std::cos(radians(40.0f)), 1.5f, 1.0f), 1.0f);
}

std::string environmentScene(const std::string& material, const std::string& render) {
    return R"({"camera": {"eye": [0, 0, 4], "target": [0, 0, 0], "fov": 35, "width": 64,
                          "height": 64},
      "background": [0.5, 0.6, 0.7], "ambient": [0, 0, 0],
      "materials": {"m": )" +
           material + R"(},
      "objects": [{"type": "sphere", "radius": 1, "material": "m"}],
      "render": )" +
           render + "}";
}

// In a uniform environment without lights a lossless dielectric returns the environment exactly
// (reflected and refracted shares add to one; a sphere has no total internal reflection), and a
// mirror returns it times its tint.
TEST(Whitted, UniformEnvironmentIsConserved) {
    const Vec3 bg(0.5f, 0.6f, 0.7f);
    for (const char* mat : {R"({"type": "dielectric", "ior": 1.5})",
                            R"({"type": "mirror", "color": [0.9, 0.8, 0.7]})"}) {
        SCOPED_TRACE(mat);
        const testing::Rendered r = testing::renderText(environmentScene(mat, "{}"));
        const bool mirror = std::string(mat).find("mirror") != std::string::npos;
        const Vec3 expected = mirror ? bg * Vec3(0.9f, 0.8f, 0.7f) : bg;
        int hits = 0;
        for (size_t i = 0; i < r.film.pixels(); ++i) {
            if (!std::isfinite(r.film.depth[i])) continue;
            ++hits;
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(r.film.color[3 * i + c], expected[c], 0.01f * expected[c]) << i;
        }
        EXPECT_GT(hits, 500);
        EXPECT_GE(r.stats.secondaryRays, static_cast<uint64_t>(hits));  // at least one each
    }
    // Absorption darkens by at most exp(-sigma * diameter) through the centre.
    const testing::Rendered r = testing::renderText(environmentScene(
        R"({"type": "dielectric", "ior": 1.5, "absorption": [0.5, 0.5, 0.5]})", "{}"));
    const size_t centre = 32 * 64 + 32;
    EXPECT_LT(r.film.color[3 * centre], bg.x * 0.9f);
    EXPECT_GT(r.film.color[3 * centre], bg.x * std::exp(-0.5f * 2.0f) * 0.95f);
}

// Keinert §3.3: with the screen-space hit criterion a hit lies up to half a pixel from the
// surface, so a small global epsilon leaves secondary rays starting on the wrong side (they strike
// the surface they left: acne, black speckles); the dynamic epsilon does not.
TEST(Whitted, DynamicEpsilonPreventsSelfIntersection) {
    const char* glass = R"({"type": "dielectric", "ior": 1.5})";
    const testing::Rendered global = testing::renderText(
        environmentScene(glass, R"({"secondary_epsilon": "global", "global_epsilon": 1e-4})"));
    const testing::Rendered dynamic =
        testing::renderText(environmentScene(glass, R"({"secondary_epsilon": "dynamic"})"));
    EXPECT_GT(global.stats.selfIntersections, global.stats.secondaryRays / 20);
    EXPECT_LE(dynamic.stats.selfIntersections, dynamic.stats.secondaryRays / 1000);
    // The acne: pixels far darker than the environment they should return.
    auto dark = [](const Film& f) {
        int n = 0;
        for (size_t i = 0; i < f.pixels(); ++i)
            n += std::isfinite(f.depth[i]) && f.color[3 * i] < 0.25f;
        return n;
    };
    EXPECT_GT(dark(global.film), 50);
    EXPECT_EQ(dark(dynamic.film), 0);
}

TEST(Whitted, ConvexityOfObjects) {
    EXPECT_TRUE(isConvex(*node::sphere(1)));
    EXPECT_TRUE(isConvex(*node::translate(
        node::intersect({node::box(Vec3(1.0f)), node::sphere(1.2f)}), Vec3(1, 2, 3))));
    EXPECT_FALSE(isConvex(*node::torus(1, 0.3f)));
    EXPECT_FALSE(isConvex(*node::unite({node::sphere(1), node::box(Vec3(0.5f))})));
    EXPECT_FALSE(isConvex(*node::plane(Vec3(0, 1, 0), 0)));
}

// Keinert §3.5: rays inside convex glass (a sphere, a rotated box, a dodecahedron, an
// intersection) jump to the bound and trace back: the same image, fewer evaluations.
TEST(Whitted, ConvexBoundsFindTheSameExitsWithFewerEvaluations) {
    auto scene = [](bool convex) {
        return std::string(R"({"camera": {"eye": [0, 1, 6], "target": [0, 0.3, 0], "width": 96,
                                          "height": 64},
          "background": [0.5, 0.6, 0.7], "ambient": [0.2, 0.2, 0.2],
          "materials": {"glass": {"type": "dielectric", "ior": 1.5, "absorption": [0.2, 0.1, 0]},
                        "floor": {"color": [0.8, 0.7, 0.6]}},
          "lights": [{"type": "directional", "direction": [-0.3, -1, -0.4]}],
          "objects": [
            {"type": "box", "size": [10, 0.2, 10], "translate": [0, -0.6, 0], "material": "floor"},
            {"type": "sphere", "radius": 0.5, "translate": [-1.5, 0, 0], "material": "glass"},
            {"type": "box", "size": [0.8, 0.8, 0.8], "rotate": [30, 40, 10], "material": "glass"},
            {"type": "dodecahedron", "radius": 0.45, "translate": [1.5, 0, 0], "material": "glass"},
            {"type": "intersection", "translate": [0, 1.2, 0], "material": "glass", "children": [
              {"type": "sphere", "radius": 0.6}, {"type": "box", "size": [0.9, 0.9, 0.9]}]}],
          "render": {"convex_bounds": )") +
               (convex ? "true" : "false") + "}}";
    };
    const testing::Rendered on = testing::renderText(scene(true));
    const testing::Rendered off = testing::renderText(scene(false));
    size_t differ = 0;
    for (size_t i = 0; i < on.film.color.size(); ++i)
        differ += std::fabs(on.film.color[i] - off.film.color[i]) > 2e-3f;
    EXPECT_LT(differ, on.film.color.size() / 200);  // grazing rays at silhouettes
    EXPECT_NEAR(double(on.stats.secondaryRays), double(off.stats.secondaryRays),
                0.01 * off.stats.secondaryRays);  // the same paths but for grazing rays
    EXPECT_LT(on.stats.secondaryEvaluations, 0.9 * off.stats.secondaryEvaluations);
}

}  // namespace
}  // namespace sdft
