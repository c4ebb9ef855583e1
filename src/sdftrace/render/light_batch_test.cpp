#include "sdftrace/render/light_batch.h"

#include <gtest/gtest.h>

#include <vector>

#include "sdftrace/exec/simd.h"
#include "sdftrace/math/sampling.h"

namespace sdft {
namespace {

Vec3 randomUnit(Rng& rng) {
    for (;;) {
        const Vec3 v(2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1);
        if (dot(v, v) > 1e-4f && dot(v, v) <= 1) return normalize(v);
    }
}

// Every hit's radiance grows by lightTerm's value, bit for bit, with AVX2 and on the baseline:
// hits lit, hidden and below the horizon, shadows partial, materials that differ from hit to hit
// (whole and fractional exponents) and shared ones, counts that are and are not multiples of
// eight.
TEST(LightBatch, AddsLightTermsValueToEveryHit) {
    const SimdLevel was = simdLevel();
    Rng rng(7);
    Light light;
    light.direction = normalize(Vec3(-1, -2, -0.5f));
    light.color = Vec3(1.0f, 0.9f, 0.7f);
    light.intensity = 1.3f;
    for (SimdLevel level : {SimdLevel::Avx2, SimdLevel::Baseline}) {
        setSimdLevel(level);
        for (int n : {0, 1, 7, 8, 13, 64, 203}) {
            for (bool shared : {true, false}) {
                std::vector<PixelMaterial> m(n);
                std::vector<Vec3> normals(n), views(n), radiance(n), want(n);
                std::vector<float> visible(n);
                for (int h = 0; h < n; ++h) {
                    if (!shared || h == 0) {
                        m[h].color = Vec3(rng.uniform(), rng.uniform(), rng.uniform());
                        m[h].diffuse = rng.uniform();
                        m[h].specular = rng.uniform();
                        const float e =
                            1 + static_cast<float>(static_cast<int>(rng.uniform() * 300));
                        m[h].shininess = rng.uniform() < 0.3f ? e + 0.5f : e;
                    } else {
                        m[h] = m[0];
                    }
                    normals[h] = randomUnit(rng);
                    views[h] = randomUnit(rng);
                    const float u = rng.uniform();
                    visible[h] = u < 0.2f ? 0.0f : (u < 0.5f ? rng.uniform() : 1.0f);
                    radiance[h] = want[h] = Vec3(rng.uniform(), rng.uniform(), rng.uniform());
                    want[h] += direct_pixel::lightTerm(light, m[h], Vec3(0.0f), normals[h],
                                                       views[h], visible[h]);
                }
                addDirectionalLight(light, m.data(), shared, normals.data(), views.data(),
                                    visible.data(), n, radiance.data());
                for (int h = 0; h < n; ++h)
                    for (int a = 0; a < 3; ++a)
                        ASSERT_EQ(radiance[h][a], want[h][a])
                            << "hit " << h << " of " << n << ", shininess " << m[h].shininess;
            }
        }
    }
    setSimdLevel(was);
}

}  // namespace
}  // namespace sdft
