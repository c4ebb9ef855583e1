#include "sdftrace/render/lighting.h"

#include <gtest/gtest.h>

#include <cmath>

namespace sdft {
namespace {

// Whole exponents by squaring agree with powf to e/2 ulp (relative 1e-5 at the largest), over
// the lobe's whole domain, underflow included; others are powf's own.
TEST(Lighting, SpecularPowerIsPowfToRounding) {
    for (int e = 1; e <= kMaxSquaredExponent; ++e) {
        for (int i = 0; i <= 1000; ++i) {
            const float x = static_cast<float>(i) / 1000.0f;
            const float want = std::pow(x, static_cast<float>(e));
            const float got = specularPower(x, static_cast<float>(e));
            // Relative where powf is a normal float; absolute where it underflows.
            const float tol = std::fmax(want * 6e-8f * static_cast<float>(e), 1e-37f);
            ASSERT_NEAR(got, want, tol) << x << "^" << e;
        }
        EXPECT_EQ(specularPower(1.0f, static_cast<float>(e)), 1.0f);
        EXPECT_EQ(specularPower(0.0f, static_cast<float>(e)), 0.0f);
    }
    for (float e : {1.5f, 31.9f, 257.0f, 1e5f})
        for (float x : {0.0f, 0.25f, 0.9f, 0.999f, 1.0f})
            EXPECT_EQ(specularPower(x, e), std::pow(x, e)) << x << "^" << e;
}

// The Blinn-Phong term: Lambert alone where the half vector is perpendicular to the normal, the
// full lobe where it is the normal.
TEST(Lighting, BlinnPhongHasItsLobeAtTheMirrorDirection) {
    const Vec3 n(0, 1, 0), color(0.5f, 0.25f, 1.0f);
    const Vec3 l = normalize(Vec3(1, 1, 0)), d = normalize(Vec3(1, -1, 0));  // mirror pair
    const Vec3 at = blinnPhong(color, 1.0f, 0.2f, 32.0f, n, l, d);
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(at[a], color[a] * dot(n, l) + 0.2f, 1e-6f);
    const Vec3 grazing = blinnPhong(color, 1.0f, 0.2f, 32.0f, n, Vec3(1, 0, 0), Vec3(-1, 0, 0));
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(grazing[a], 0.0f, 1e-6f);
}

}  // namespace
}  // namespace sdft
