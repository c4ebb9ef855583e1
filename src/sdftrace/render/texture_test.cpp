#include "sdftrace/render/texture.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sdftrace/field/noise.h"
#include "sdftrace/math/sampling.h"

namespace sdft {
namespace {

Texture procedural(Texture::Kind kind) {
    Texture t;
    t.kind = kind;
    return t;
}

Vec3 randomPoint(Rng& rng, float extent) {
    return Vec3(rng.uniform(), rng.uniform(), rng.uniform()) * (2 * extent) - Vec3(extent);
}

TEST(Texture, CheckerAlternatesBetweenUnitCells) {
    const Texture t = procedural(Texture::Kind::Checker);
    Rng rng(1, 2, 3);
    for (int i = 0; i < 1000; ++i) {
        const Vec3 q = randomPoint(rng, 20);
        const float s = proceduralPattern(t, q);
        ASSERT_TRUE(s == 0 || s == 1);
        for (int a = 0; a < 3; ++a) {
            Vec3 r = q;
            r[a] += 1;
            ASSERT_EQ(proceduralPattern(t, r), 1 - s) << a;
        }
    }
}

// Every pattern stays in [0, 1]; noise is centred on 1/2; turbulence spends time near 0 (the
// creases of |noise|) and is not constant.
TEST(Texture, ProceduralPatternsStayInRange) {
    for (auto kind : {Texture::Kind::Noise, Texture::Kind::Turbulence, Texture::Kind::Marble,
                      Texture::Kind::Wood}) {
        SCOPED_TRACE(static_cast<int>(kind));
        const Texture t = procedural(kind);
        Rng rng(4, 5, 6);
        double sum = 0, sq = 0;
        const int n = 20000;
        for (int i = 0; i < n; ++i) {
            const float s = proceduralPattern(t, randomPoint(rng, 50));
            ASSERT_GE(s, 0.0f);
            ASSERT_LE(s, 1.0f);
            sum += s;
            sq += s * s;
        }
        const double mean = sum / n, sd = std::sqrt(sq / n - mean * mean);
        EXPECT_GT(sd, 0.05);  // a pattern, not a constant
        if (kind == Texture::Kind::Noise) {
            EXPECT_NEAR(mean, 0.5, 0.03);
        }
    }
}

// Liktor §5.5.1: each octave doubles the frequency and halves the amplitude, so more octaves add
// fine detail: the mean difference between points 1/1024 apart (where every octave is smooth)
// grows with the octave count, like the square root of it (independent gradients).
TEST(Texture, OctavesAddFineDetail) {
    auto roughness = [](int octaves) {
        Texture t = procedural(Texture::Kind::Noise);
        t.octaves = octaves;
        Rng rng(7, 8, 9);
        double sum = 0;
        for (int i = 0; i < 5000; ++i) {
            const Vec3 q = randomPoint(rng, 10);
            sum += std::fabs(proceduralPattern(t, q) - proceduralPattern(t, q + Vec3(1.0f / 1024)));
        }
        return sum / 5000;
    };
    const double r1 = roughness(1), r4 = roughness(4), r8 = roughness(8);
    EXPECT_GT(r4, 1.5 * r1);
    EXPECT_GT(r8, 1.2 * r4);
}

// Without turbulence, marble's stripes repeat every unit along the axis and wood's rings depend on
// the distance from the axis only.
TEST(Texture, MarbleAndWoodFollowTheirAxis) {
    Texture marble = procedural(Texture::Kind::Marble);
    marble.strength = 0;
    marble.axis = 0;
    Texture wood = procedural(Texture::Kind::Wood);
    wood.strength = 0;
    wood.axis = 1;
    Rng rng(10, 11, 12);
    for (int i = 0; i < 1000; ++i) {
        const Vec3 q = randomPoint(rng, 5);
        ASSERT_NEAR(proceduralPattern(marble, q), proceduralPattern(marble, q + Vec3(1, 0, 0)),
                    1e-3f);
        ASSERT_NEAR(proceduralPattern(marble, q),
                    proceduralPattern(marble, q + Vec3(0, 0.37f, -1.3f)), 1e-6f);
        const float c = std::cos(0.7f), s = std::sin(0.7f);
        const Vec3 turned(c * q.x - s * q.z, q.y + 2.5f, s * q.x + c * q.z);
        ASSERT_NEAR(proceduralPattern(wood, q), proceduralPattern(wood, turned), 1e-3f);
    }
}

TextureImage gradientImage() {
    // 4 x 2: red rises to the right, green marks the top row.
    TextureImage img;
    img.width = 4;
    img.height = 2;
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) {
            img.rgb.push_back(0.25f * x);
            img.rgb.push_back(y == 0 ? 1.0f : 0.0f);
            img.rgb.push_back(0.5f);
        }
    return img;
}

TEST(Texture, ImageSamplesTexelCentresBilinearlyAndRepeats) {
    const TextureImage img = gradientImage();
    // Texel (x, y) centre: u = (x + 0.5) / 4, v = 1 - (y + 0.5) / 2 (v up).
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) {
            const Vec3 c = img.sample((x + 0.5f) / 4, 1 - (y + 0.5f) / 2);
            EXPECT_NEAR(c.x, 0.25f * x, 1e-5f);
            EXPECT_NEAR(c.y, y == 0 ? 1.0f : 0.0f, 1e-5f);
        }
    // Halfway between texels 1 and 2; and the same point one repeat over.
    EXPECT_NEAR(img.sample(0.5f, 0.75f).x, 0.375f, 1e-5f);
    EXPECT_NEAR(img.sample(2.5f, -0.25f).x, 0.375f, 1e-5f);
}

// Liktor §4.2.2: tri-planar projection weights the three planes by the normal; facing an axis it
// is that axis's planar projection, and a uniform texture stays uniform whatever the normal.
TEST(Texture, TriplanarBlendsPlanarProjectionsByTheNormal) {
    std::vector<TextureImage> images{gradientImage()};
    Texture tri;
    tri.kind = Texture::Kind::Image;
    tri.image = 0;
    tri.projection = Texture::Projection::Triplanar;
    tri.scale = 2;
    Texture planar = tri;
    planar.projection = Texture::Projection::Planar;
    Rng rng(13, 14, 15);
    for (int i = 0; i < 200; ++i) {
        TextureInputs in;
        in.point = randomPoint(rng, 3);
        for (int a = 0; a < 3; ++a) {
            in.normal = Vec3(0.0f);
            in.normal[a] = i % 2 ? 1.0f : -1.0f;
            planar.axis = a;
            const Vec3 x = evalTexture(tri, images, in), y = evalTexture(planar, images, in);
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(x[c], y[c], 1e-6f);
        }
    }
    TextureImage flat;
    flat.width = flat.height = 3;
    flat.rgb.assign(27, 0.4f);
    images = {flat};
    for (int i = 0; i < 200; ++i) {
        TextureInputs in;
        in.point = randomPoint(rng, 3);
        in.normal = normalize(randomPoint(rng, 1) + Vec3(1e-3f));
        EXPECT_NEAR(evalTexture(tri, images, in).y, 0.4f, 1e-5f);
    }
}

// A texture-coordinate projection uses the grid's (u, v) where there are some and falls back to
// tri-planar elsewhere.
TEST(Texture, GridProjectionUsesStoredCoordinates) {
    std::vector<TextureImage> images{gradientImage()};
    Texture t;
    t.kind = Texture::Kind::Image;
    t.image = 0;
    t.projection = Texture::Projection::Grid;
    TextureInputs in;
    in.point = Vec3(0.3f, 0.2f, 0.1f);
    in.normal = Vec3(0, 1, 0);
    in.hasUv = true;
    in.u = 3.5f / 4;
    in.v = 0.25f;
    EXPECT_NEAR(evalTexture(t, images, in).x, 0.75f, 1e-5f);
    in.hasUv = false;
    Texture tri = t;
    tri.projection = Texture::Projection::Triplanar;
    EXPECT_NEAR(evalTexture(t, images, in).x, evalTexture(tri, images, in).x, 1e-6f);
}

}  // namespace
}  // namespace sdft
