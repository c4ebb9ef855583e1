#include "sdftrace/render/temporal.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sdftrace/scene/plan_render.h"
#include "test_scenes/shadow_test_scenes.h"

namespace sdft {
namespace {

double rmse(const std::vector<float>& a, const std::vector<float>& b) {
    double sq = 0;
    for (size_t i = 0; i < a.size(); ++i) sq += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
    return std::sqrt(sq / a.size());
}

// Stills: k frames of one jittered light sample each average like k samples in one frame.
TEST(Temporal, AccumulatedFramesConvergeToTheGroundTruth) {
    auto scene = [](int rays) {
        Scene s = parseSceneText(
            testing::shadowScene(
                testing::kSphereLight,
                R"({"shadow_method": "distributed", "shadow_rays": )" + std::to_string(rays) + "}"),
            "<test>");
        s.camera.width = 96;
        s.camera.height = 60;
        return s;
    };
    auto colour = [](const Scene& s, int frames) {
        Film film(s.camera.width, s.camera.height);
        TemporalOptions o;
        o.frames = frames;
        o.jitterCamera = false;  // the same pixel footprints as the truth
        renderFrames(planRender(s), film, o);
        return film.color;
    };
    const std::vector<float> truth = colour(scene(1024), 1);
    const double one = rmse(colour(scene(1), 1), truth);
    const double accumulated = rmse(colour(scene(1), 64), truth);
    const double many = rmse(colour(scene(64), 1), truth);
    EXPECT_LT(accumulated, 0.25 * one) << "one frame " << one << ", 64 frames " << accumulated;
    EXPECT_LT(accumulated, 2.0 * many) << "64 rays in one frame " << many;
}

// Animation: the camera orbits; the reprojected, clamped history leaves no ghost. The last
// accumulated frame stays close to a single render from the last camera, and the orbit returns.
TEST(Temporal, OrbitingCameraLeavesNoGhosts) {
    Scene s = parseSceneText(
        testing::shadowScene(testing::kSphereLight, R"({"shadow_method": "soft"})"), "<test>");
    const CameraDesc full = orbitCamera(s.camera, 360.0f);
    EXPECT_LT(length(full.eye - s.camera.eye), 1e-4f * length(s.camera.eye));
    EXPECT_NEAR(length(orbitCamera(s.camera, 37.0f).eye - s.camera.target),
                length(s.camera.eye - s.camera.target), 1e-4f);
    const int frames = 10;
    const float step = 4.0f;
    Film film(s.camera.width, s.camera.height);
    TemporalOptions o;
    o.frames = frames;
    o.orbitDegrees = step;
    int seen = 0;
    renderFrames(planRender(s), film, o, [&](int k, const Film&) { seen += k == seen; });
    EXPECT_EQ(seen, frames);
    Scene last = s;
    last.camera = orbitCamera(s.camera, step * (frames - 1));
    Film single(s.camera.width, s.camera.height);
    render(planRender(last), single);
    double diff = 0, mean = 0;
    for (size_t i = 0; i < single.color.size(); ++i) {
        diff += std::fabs(double(film.color[i]) - single.color[i]);
        mean += single.color[i];
    }
    EXPECT_LT(diff / mean, 0.05);  // a ghost of the box or the plate would leave far more
    EXPECT_GT(diff, 0.0);          // the history was used
}

}  // namespace
}  // namespace sdft
