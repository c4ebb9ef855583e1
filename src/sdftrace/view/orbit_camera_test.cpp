#include "sdftrace/view/orbit_camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace sdft {
namespace {

CameraDesc home() {
    CameraDesc c;
    c.eye = {0, 1, 5};
    c.target = {0, 1, 0};
    c.up = {0, 1, 0};
    c.fovDeg = 40;
    c.width = 200;
    c.height = 100;
    return c;
}

float degrees(float radians) { return radians * 180.0f / 3.14159265f; }

TEST(OrbitCamera, OrbitKeepsTheDistanceAndTurnsByTheDragsAngle) {
    OrbitCamera cam(home());
    cam.orbit(360, 0);  // 90 degrees of yaw about +y
    const CameraDesc& c = cam.camera();
    EXPECT_NEAR(length(c.eye - c.target), 5.0f, 1e-4f);
    EXPECT_NEAR(c.eye.y, 1.0f, 1e-4f);
    EXPECT_NEAR(std::fabs(c.eye.x), 5.0f, 1e-3f);  // now looking along x
    // A drag down by 40 pixels (10 degrees) lifts the eye by 10 degrees.
    cam.orbit(0, 40);
    const Vec3 offset = cam.camera().eye - cam.camera().target;
    EXPECT_NEAR(degrees(std::asin(offset.y / length(offset))), 10.0f, 1e-2f);
    EXPECT_NEAR(length(offset), 5.0f, 1e-4f);
}

TEST(OrbitCamera, PitchStopsShortOfThePoles) {
    OrbitCamera cam(home());
    cam.orbit(0, 100000);
    const Vec3 offset = cam.camera().eye - cam.camera().target;
    EXPECT_NEAR(degrees(std::acos(offset.y / length(offset))), 1.0f, 1e-2f);
    cam.orbit(0, -100000);
    const Vec3 below = cam.camera().eye - cam.camera().target;
    EXPECT_NEAR(degrees(std::acos(below.y / length(below))), 179.0f, 1e-2f);
    EXPECT_TRUE(std::isfinite(cam.camera().eye.x));
}

TEST(OrbitCamera, PanMovesThePointUnderTheCursorWithIt) {
    OrbitCamera cam(home());
    // 100 pixels of a 100-pixel-high image at distance 5 and fov 40: 2 * 5 * tan(20 deg).
    cam.pan(0, 100);
    const float expected = 2 * 5 * std::tan(20 * 3.14159265f / 180);
    EXPECT_NEAR(cam.camera().target.y - 1.0f, expected, 1e-4f);
    EXPECT_NEAR(cam.camera().eye.y - 1.0f, expected, 1e-4f);
    cam.pan(50, 0);  // dragging right moves the view left
    EXPECT_NEAR(cam.camera().target.x, -expected / 2, 1e-4f);
}

TEST(OrbitCamera, ZoomFliesAndResetGoesHome) {
    OrbitCamera cam(home());
    cam.zoom(2);
    EXPECT_NEAR(length(cam.camera().eye - cam.camera().target), 5 * 0.85f * 0.85f, 1e-4f);
    cam.zoom(-1000);  // far out, still finite
    EXPECT_TRUE(std::isfinite(cam.camera().eye.z));
    cam.zoom(100000);  // never onto the target
    EXPECT_GT(length(cam.camera().eye - cam.camera().target), 0.0f);
    cam.reset();
    cam.fly(1, 0, 0);
    EXPECT_NEAR(cam.camera().eye.z, 4.0f, 1e-5f);
    EXPECT_NEAR(cam.camera().target.z, -1.0f, 1e-5f);
    cam.setSize(64, 32);
    cam.reset();
    EXPECT_EQ(cam.camera().eye.z, 5.0f);
    EXPECT_EQ(cam.camera().width, 64);  // the window's size stays
}

TEST(OrbitCamera, TheFlagsReproduceTheFloatsExactly) {
    OrbitCamera cam(home());
    cam.orbit(37, 11);
    const std::string flags = cam.cliFlags();
    Vec3 eye;
    ASSERT_EQ(std::sscanf(flags.c_str(), "--eye %f,%f,%f", &eye.x, &eye.y, &eye.z), 3) << flags;
    EXPECT_EQ(eye.x, cam.camera().eye.x);
    EXPECT_EQ(eye.y, cam.camera().eye.y);
    EXPECT_EQ(eye.z, cam.camera().eye.z);
    EXPECT_NE(flags.find("--width 200 --height 100"), std::string::npos);
}

}  // namespace
}  // namespace sdft
