#include "sdftrace/field/noise.h"

#include <gtest/gtest.h>

#include "sdftrace/field/test_util.h"

namespace sdft {
namespace {

TEST(Noise, GradientStaysUnderTheDeclaredLipschitzBound) {
    testing::Rng rng(9);
    float worst = 0;
    const float h = 1e-3f;
    for (int i = 0; i < 1000000; ++i) {
        Vec3 p = rng.inCube(50);
        Vec3 g((noise::perlin(p + Vec3(h, 0, 0)) - noise::perlin(p - Vec3(h, 0, 0))) / (2 * h),
               (noise::perlin(p + Vec3(0, h, 0)) - noise::perlin(p - Vec3(0, h, 0))) / (2 * h),
               (noise::perlin(p + Vec3(0, 0, h)) - noise::perlin(p - Vec3(0, 0, h))) / (2 * h));
        worst = std::fmax(worst, length(g));
    }
    EXPECT_LT(worst, noise::kPerlinLipschitz);
    EXPECT_GT(worst, 1.0f);  // the bound is not vacuous
}

TEST(Noise, ValueRangeWithinDeclaredMaximum) {
    testing::Rng rng(10);
    for (int i = 0; i < 200000; ++i) {
        ASSERT_LE(std::fabs(noise::fbm(rng.inCube(30), 4, 0.5f)), noise::fbmMaxAbs(4, 0.5f));
    }
}

}  // namespace
}  // namespace sdft
