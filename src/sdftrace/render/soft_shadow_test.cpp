#include "sdftrace/render/soft_shadow.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "sdftrace/field/node.h"
#include "test_scenes/shadow_test_scenes.h"

namespace sdft {
namespace {

using testing::kSphereLight;
using testing::renderText;
using testing::shadowScene;

// Distributed shadow rays against the closed form: a sphere occluder centred on the line from the
// receiver to a sphere light hides the cap of half-angle beta out of the light's alpha, so the
// visible share is 1 - (1 - cos beta) / (1 - cos alpha) (both uniform in solid angle).
TEST(DistributedShadows, MatchTheClosedFormOfConcentricCaps) {
    const float D = 5, R = 1, d = 2;
    for (float r : {0.1f, 0.2f, 0.3f}) {
        const std::string text =
            R"({"camera": {"eye": [0, 1, 3], "target": [0, 0, 0], "fov": 10, "width": 5,
                           "height": 5},
              "lights": [{"type": "sphere", "position": [0, )" +
            std::to_string(D) + R"(, 0], "radius": )" + std::to_string(R) + R"(}],
              "objects": [{"type": "plane", "normal": [0, 1, 0]},
                          {"type": "sphere", "radius": )" +
            std::to_string(r) + R"(, "translate": [0, )" + std::to_string(d) + R"(, 0]}],
              "render": {"shadow_method": "distributed", "shadow_rays": 4096,
                         "screen_space": false}})";
        testing::Rendered out = renderText(text);
        const float cosA = std::sqrt(1 - (R / D) * (R / D)),
                    cosB = std::sqrt(1 - (r / d) * (r / d));
        const float expected = 1 - (1 - cosB) / (1 - cosA);
        // The centre pixel looks at the origin (without the screen-space hit criterion, which
        // stops within half a pixel of these wide pixels); 4096 stratified samples.
        EXPECT_NEAR(out.film.shadow[2 * 5 + 2], expected, 0.01f) << "occluder radius " << r;
    }
}

// RTSDF §2.4-2.5 against the ground truth. The paper's estimate is 0 wherever the hard shadow ray
// is blocked and widens penumbrae outwards (its fig. 16), so over the penumbrae it strays further
// from the distributed rays than the hard shadow does; the centred estimate straddles the hard
// edge and comes closer than both. Every estimate stays finite in [0, 1].
TEST(SoftShadows, CenteredEstimateApproximatesTheGroundTruthBest) {
    auto shadow = [](const char* method, const char* extra = "") {
        return renderText(
                   shadowScene(kSphereLight, std::string(R"({"shadow_method": ")") + method +
                                                 R"(", "shadow_rays": 256, "soft_max_step": 0.05)" +
                                                 extra + "}"))
            .film.shadow;
    };
    const std::vector<float> truth = shadow("distributed"), hard = shadow("hard"),
                             centered = shadow("soft"),
                             paper = shadow("soft", R"(, "soft_centered": false)"),
                             classic = shadow("soft", R"(, "soft_centered": false,
                                                          "soft_triangulation": false)");
    double hardErr = 0, centeredErr = 0, paperErr = 0;
    int penumbra = 0;
    for (size_t i = 0; i < truth.size(); ++i) {
        for (const std::vector<float>* v : {&centered, &paper, &classic})
            ASSERT_TRUE(std::isfinite((*v)[i]) && (*v)[i] >= 0 && (*v)[i] <= 1) << i;
        if (hard[i] == 0) {  // up to grazing rays the two tracers decide differently
            EXPECT_LT(paper[i], 0.02f) << i;
            EXPECT_LT(classic[i], 0.02f) << i;
        }
        if (truth[i] <= 0.02f || truth[i] >= 0.98f) continue;
        ++penumbra;
        hardErr += std::fabs(hard[i] - truth[i]);
        centeredErr += std::fabs(centered[i] - truth[i]);
        paperErr += std::fabs(paper[i] - truth[i]);
    }
    ASSERT_GT(penumbra, 150);
    EXPECT_LT(centeredErr, 0.7 * hardErr)
        << "mean centred error " << centeredErr / penumbra << ", hard " << hardErr / penumbra;
    EXPECT_GT(paperErr, hardErr) << "the paper's outward penumbra";
    std::printf("penumbra pixels %d, mean error: hard %.3f, centred %.3f, RTSDF %.3f\n", penumbra,
                hardErr / penumbra, centeredErr / penumbra, paperErr / penumbra);
}

// One march past a unit sphere at the origin, its exact distance, whose direction clears the
// sphere by half the light's angular radius (rho): from 3 units away, phi from the centre's
// direction, the angular clearance is phi - asin(1/3). However far the march runs on (a
// directional light's runs to max_distance; beyond the sphere each step doubles), the estimate
// keeps that clearance: each method within 0.2 light radii of it, a receding ray fully lit.
TEST(SoftShadows, MarchesRunningFarPastTheSceneKeepTheirClearance) {
    const float rho = 0.1f, phi = std::asin(1.0f / 3.0f) + 0.5f * rho;
    const Vec3 origin{-3, 0, 0}, dir{std::cos(phi), std::sin(phi), 0};
    auto march = [&](Vec3 d, float tMax, bool triangulate, bool centered) {
        SoftShadowOptions o;
        o.triangulate = triangulate;
        o.centered = centered;
        o.jitter = false;
        SoftShadowMarch m;
        m.start(origin, d, 0.0f, tMax, std::tan(rho), o, 0.0f);
        while (m.active()) m.step(length(m.point()) - 1.0f, o);
        return m.result();
    };
    for (float tMax : {10.0f, 1e3f, 1e6f}) {
        for (bool triangulate : {true, false}) {
            SCOPED_TRACE(std::to_string(tMax) + (triangulate ? " triangulated" : " k h/t"));
            const SoftShadowResult paper = march(dir, tMax, triangulate, false);
            EXPECT_NEAR(paper.visibility, 0.5f, 0.2f);
            EXPECT_LT(paper.evaluations, 256);
            EXPECT_NEAR(march(dir, tMax, triangulate, true).visibility,
                        SoftShadowMarch::diskShare(0.5f),
                        SoftShadowMarch::diskShare(0.7f) - SoftShadowMarch::diskShare(0.5f));
            EXPECT_EQ(march(Vec3{-1, 0, 0}, tMax, triangulate, true).visibility, 1.0f);
        }
    }
}

// A sun's march ends where it leaves the scene's bounds: the same visibility as the march run on
// to max_distance (100), at a fraction of the evaluations (with a max step of 0.05 every lit
// march ran to maxSteps); the tile renderer's packets end the same way.
TEST(SoftShadows, MarchesEndWhereTheRayLeavesTheScene) {
    const Tape tape =
        compileTape(node::unite({node::translate(node::box({3, 0.1f, 3}), {0, -0.1f, 0}),
                                 node::translate(node::sphere(0.5f), {0, 1, 0})}));
    TapeView unbounded = tape.view();
    unbounded.bounds = Bounds3::everything();
    const Vec3 toSun = normalize(Vec3(0.3f, 1, 0.2f));
    const float tanRadius = std::tan(2 * kPi / 180);
    for (bool centered : {true, false}) {
        SoftShadowOptions o;
        o.maxStep = 0.05f;
        o.jitter = false;
        o.centered = centered;
        std::vector<SoftShadowRay> rays;
        long clippedEvals = 0, fullEvals = 0;
        std::vector<float> clipped;
        int penumbra = 0;
        for (float x = -1.5f; x <= 1.5f; x += 0.1f) {
            for (float z = -1.5f; z <= 1.5f; z += 0.1f) {
                const Vec3 origin(x, 1e-3f, z);
                const SoftShadowResult a =
                    softShadowTape(tape.view(), origin, toSun, 0, 100, tanRadius, o, 0);
                const SoftShadowResult b =
                    softShadowTape(unbounded, origin, toSun, 0, 100, tanRadius, o, 0);
                EXPECT_NEAR(a.visibility, b.visibility, 0.01f) << x << ", " << z;
                penumbra += a.visibility > 0.05f && a.visibility < 0.95f;
                clippedEvals += a.evaluations;
                fullEvals += b.evaluations;
                clipped.push_back(a.visibility);
                rays.push_back({origin, toSun, 0, 100, tanRadius, 0});
            }
        }
        EXPECT_GT(penumbra, 10);
        EXPECT_LT(clippedEvals * 4, fullEvals) << clippedEvals << " against " << fullEvals;
        std::vector<SoftShadowResult> packet;
        SoftShadowScratch scratch;
        softShadowPacket(tape, rays, o, packet, scratch);
        long packetEvals = 0;
        for (size_t i = 0; i < rays.size(); ++i) {
            EXPECT_NEAR(packet[i].visibility, clipped[i], 1e-3f) << i;
            packetEvals += packet[i].evaluations;
        }
        EXPECT_LT(packetEvals, clippedEvals + clippedEvals / 10);
    }
}

// A point light has no penumbra: the soft estimate is the hard shadow.
TEST(SoftShadows, PointLightsGiveHardShadows) {
    const char* light = R"({"type": "point", "position": [-2.5, 5, 1.5], "intensity": 30})";
    const std::vector<float> hard =
        renderText(shadowScene(light, R"({"shadow_method": "hard"})")).film.shadow;
    const std::vector<float> soft =
        renderText(shadowScene(light, R"({"shadow_method": "soft"})")).film.shadow;
    size_t differ = 0;
    for (size_t i = 0; i < hard.size(); ++i) {
        EXPECT_TRUE(soft[i] == 0.0f || soft[i] == 1.0f) << i;
        differ += soft[i] != hard[i];
    }
    EXPECT_LE(differ, hard.size() / 200);  // grazing rays near edges may differ
}

}  // namespace
}  // namespace sdft
