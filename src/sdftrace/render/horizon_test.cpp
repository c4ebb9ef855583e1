#include "sdftrace/render/horizon.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sdftrace/field/node.h"
#include "sdftrace/render/film.h"
#include "sdftrace/render/primary_pixel.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"

namespace sdft {
namespace {

TEST(Horizon, TopLevelPlanesAndTheBoundsOfTheRest) {
    const NodePtr floor = node::plane(Vec3(0, 1, 0), 0.5f);
    const NodePtr ball = node::translate(node::sphere(1.0f), Vec3(0, 1, 0));
    HorizonPlanes h = horizonPlanes(node::unite({floor, ball}));
    ASSERT_EQ(h.count, 1);
    EXPECT_EQ(h.plane[0][1], 1.0f);
    EXPECT_EQ(h.plane[0][3], 0.5f);
    EXPECT_TRUE(h.rest.finite());
    EXPECT_NEAR(h.rest.hi.y, 2.0f, 1e-5f);
    h = horizonPlanes(floor);  // the plane alone: nothing else to leave
    EXPECT_EQ(h.count, 1);
    EXPECT_TRUE(h.rest.empty());
    // Something else unbounded (a second, tilted plane inside a difference): no horizon.
    EXPECT_EQ(
        horizonPlanes(node::unite({floor, node::subtract(node::plane(Vec3(1, 0, 0), 0), ball)}))
            .count,
        0);
    EXPECT_EQ(horizonPlanes(ball).count, 0);
}

TEST(Horizon, RaysMeetThePlaneAnalyticallyOnlyPastTheRest) {
    HorizonPlanes h = horizonPlanes(node::unite(
        {node::plane(Vec3(0, 1, 0), 0.0f), node::translate(node::sphere(1.0f), Vec3(0, 1, 0))}));
    float t = 0;
    // Grazing, from high above: met at height / sin(angle), far past the sphere.
    const Vec3 dir = normalize(Vec3(0, -1e-3f, -1));
    ASSERT_TRUE(horizonHit(h, {Vec3(0, 5, 10), dir}, t));
    EXPECT_NEAR(t, 5.0f / -dir.y, 1e-4f * t);
    // The plane met before the ray leaves the rest's bounds (a sphere sunk into the floor): the
    // march decides.
    const HorizonPlanes sunk =
        horizonPlanes(node::unite({node::plane(Vec3(0, 1, 0), 0.0f), node::sphere(1.0f)}));
    EXPECT_FALSE(horizonHit(sunk, {Vec3(0, 5, 0), Vec3(0, -1, 0)}, t));
    EXPECT_TRUE(horizonHit(sunk, {Vec3(0, 5, 3), Vec3(0, -1, 0)}, t));
    EXPECT_NEAR(t, 5.0f, 1e-6f);
    // Upwards, or from below the floor.
    EXPECT_FALSE(horizonHit(h, {Vec3(0, 5, 10), Vec3(0, 1, 0)}, t));
    EXPECT_FALSE(horizonHit(h, {Vec3(0, -1, 10), Vec3(0, -1, 0)}, t));
    EXPECT_FALSE(horizonHit(HorizonPlanes{}, {Vec3(0, 5, 10), dir}, t));
}

// A floor seen from afar reaches the horizon: every pixel below the horizon line hits it at the
// plane's distance, every pixel above misses, and the object far away still shows (the automatic
// t_max reaches past it, not the plane). Before, the floor ended in a curve where t_max cut it and
// objects past 100 were gone. The CPU renderer's packets and the per-pixel code the GPU runs
// (tracePrimaryPixel) agree.
TEST(Horizon, AFloorFromAfarReachesTheHorizon) {
    const char* far = R"({"camera": {"eye": [0, 30, 400], "target": [0, 0.7, 0], "fov": 38,
                                     "width": 64, "height": 36},
                          "objects": [{"type": "plane", "normal": [0, 1, 0], "distance": 0},
                                      {"type": "sphere", "radius": 20, "translate": [0, 20, 0]}]})";
    const RenderPlan plan = planRender(parseSceneText(far, "far.json"));
    EXPECT_LT(plan.settings.maxDistance, 500.0f);  // past the sphere, not the plane
    Film film(64, 36);
    render(plan, film);
    FrameView frame;
    frame.camera = plan.camera;
    const PrimaryPixelView view = primaryPixelView(plan, frame);
    const Camera camera(plan.camera);
    int below = 0, above = 0, sphere = 0;
    for (int y = 0; y < 36; ++y)
        for (int x = 0; x < 64; ++x) {
            const Ray ray = camera.rayThrough(x + 0.5f, y + 0.5f);
            const float depth = film.depth[static_cast<size_t>(y) * 64 + x];
            const PrimaryPixel px = tracePrimaryPixel(view, x, y);
            EXPECT_EQ(px.trace.hit, std::isfinite(depth)) << x << " " << y;
            if (ray.direction.y >= 0) {  // the sky, or the sphere's top
                if (std::isfinite(depth)) {
                    EXPECT_LT(depth, 430.0f) << x << " " << y;
                    ++sphere;
                } else {
                    ++above;
                }
                continue;
            }
            const float floor = ray.origin.y / -ray.direction.y;
            ASSERT_TRUE(std::isfinite(depth)) << x << " " << y;
            EXPECT_NEAR(px.trace.t, depth, 1e-3f * depth) << x << " " << y;
            if (depth < 0.99f * floor) {
                ++sphere;  // the sphere, in front of the floor
                continue;
            }
            EXPECT_NEAR(depth, floor, 1e-3f * floor) << x << " " << y;
            ++below;
        }
    EXPECT_GT(above, 200);
    EXPECT_GT(below, 800);
    EXPECT_GT(sphere, 0);
}

}  // namespace
}  // namespace sdft
