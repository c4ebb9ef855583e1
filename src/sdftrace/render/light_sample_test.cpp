#include "sdftrace/render/light_sample.h"

#include <gtest/gtest.h>

#include <cmath>

namespace sdft {
namespace {

// Every sample lies on the light: on a sphere light's near surface, inside a rectangle; directions
// are unit and the sphere's samples fill the cone it subtends (its axis is their mean).
TEST(LightSample, SamplesLieOnTheLight) {
    Light sphere;
    sphere.kind = Light::Kind::Sphere;
    sphere.position = {1, 4, -2};
    sphere.radius = 0.7f;
    Light rect;
    rect.kind = Light::Kind::Rect;
    rect.position = {-1, 3, 0};
    rect.u = {2, 0, 0};
    rect.v = {0, 0.5f, 1};
    const Vec3 p(0.2f, 0, 0.3f);
    Rng rng(7);
    Vec3 mean(0.0f);
    for (int i = 0; i < 4000; ++i) {
        const LightSample s = sampleLight(sphere, p, rng.uniform(), rng.uniform());
        EXPECT_NEAR(length(s.dir), 1.0f, 1e-5f);
        EXPECT_NEAR(length(p + s.dir * s.dist - sphere.position), sphere.radius, 1e-4f);
        // The near side: the surface normal there faces p.
        EXPECT_LT(dot(p + s.dir * s.dist - sphere.position, s.dir), 1e-4f);
        mean += s.dir;
        const LightSample r = sampleLight(rect, p, rng.uniform(), rng.uniform());
        const Vec3 q = p + r.dir * r.dist - rect.position;
        const Vec3 n = normalize(cross(rect.u, rect.v));
        EXPECT_NEAR(dot(q, n), 0.0f, 1e-4f);
        EXPECT_LE(std::fabs(dot(q, rect.u) / dot(rect.u, rect.u)), 0.5f + 1e-4f);
        EXPECT_LE(std::fabs(dot(q, rect.v) / dot(rect.v, rect.v)), 0.5f + 1e-4f);
    }
    EXPECT_GT(dot(normalize(mean), normalize(sphere.position - p)), 0.9999f);
    // The angular radius the penumbra estimate uses.
    const float d = length(sphere.position - p);
    EXPECT_NEAR(std::atan(lightTanRadius(sphere, p)), std::asin(sphere.radius / d), 1e-5f);
    Light sun;
    sun.angle = radians(0.5f);
    EXPECT_NEAR(lightTanRadius(sun, p), std::tan(sun.angle / 2), 1e-7f);
    const LightSample s = sampleLight(sun, p, 0.3f, 0.8f);
    EXPECT_LE(std::acos(std::min(1.0f, dot(s.dir, normalize(-sun.direction)))),
              sun.angle / 2 + 1e-4f);
    EXPECT_TRUE(std::isinf(s.dist));
}

}  // namespace
}  // namespace sdft
