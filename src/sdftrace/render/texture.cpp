#include "sdftrace/render/texture.h"

#include <algorithm>
#include <cmath>

#include "sdftrace/field/noise.h"

namespace sdft {

namespace {

constexpr float kTwoPi = 6.28318531f;

float fract(float x) { return x - std::floor(x); }

// Sum of the octave amplitudes: fbm / norm and turbulence / norm stay within about [-1, 1].
float octaveNorm(const Texture& t) {
    float sum = 0, amp = 1;
    for (int i = 0; i < t.octaves; ++i, amp *= t.gain) sum += amp;
    return std::max(sum, 1e-6f);
}

// The two coordinates a planar projection along `axis` keeps: x -> (z, y), y -> (x, z),
// z -> (x, y).
void planarUv(Vec3 q, int axis, float& u, float& v) {
    switch (axis) {
        case 0:
            u = q.z, v = q.y;
            return;
        case 1:
            u = q.x, v = q.z;
            return;
        default:
            u = q.x, v = q.y;
            return;
    }
}

// A 2D texture at (u, v): the image, or the procedural pattern on the plane z = 0.
Vec3 sample2D(const Texture& t, const std::vector<TextureImage>& images, float u, float v) {
    if (t.kind == Texture::Kind::Image) {
        if (t.image < 0 || t.image >= static_cast<int>(images.size())) return Vec3(0.0f);
        return images[static_cast<size_t>(t.image)].sample(u, v);
    }
    const float s = proceduralPattern(t, Vec3(u, v, 0.0f));
    return t.colors[0] * (1 - s) + t.colors[1] * s;
}

}  // namespace

Vec3 TextureImage::sample(float u, float v) const {
    if (width <= 0 || height <= 0) return Vec3(0.0f);
    // Texel centres at (i + 0.5) / width; v up.
    const float x = fract(u) * width - 0.5f, y = (1 - fract(v)) * height - 0.5f;
    const float fx = std::floor(x), fy = std::floor(y);
    const float ax = x - fx, ay = y - fy;
    auto wrap = [](int i, int n) { return ((i % n) + n) % n; };
    Vec3 c(0.0f);
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            const int i = wrap(static_cast<int>(fx) + dx, width);
            const int j = wrap(static_cast<int>(fy) + dy, height);
            const size_t p = 3 * (static_cast<size_t>(j) * width + i);
            const float w = (dx ? ax : 1 - ax) * (dy ? ay : 1 - ay);
            c += Vec3(rgb[p], rgb[p + 1], rgb[p + 2]) * w;
        }
    return c;
}

// Liktor 2008, §5.5.1 (after Perlin 1985 and Watt & Watt 1992, ch. 7): octaves double the
// frequency and scale the amplitude by `gain`.
float proceduralPattern(const Texture& t, Vec3 q) {
    switch (t.kind) {
        case Texture::Kind::Checker: {
            const int s = static_cast<int>(std::floor(q.x) + std::floor(q.y) + std::floor(q.z));
            return static_cast<float>(s & 1);
        }
        // fbm sums to about [-1, 1] and turbulence to about [0, 1] for the default gain (octave
        // amplitudes 1, 1/2, ... times Perlin's typical |value| of about 0.5).
        case Texture::Kind::Noise:
            return std::clamp(0.5f + 0.5f * noise::fbm(q, t.octaves, t.gain), 0.0f, 1.0f);
        case Texture::Kind::Turbulence:
            return std::clamp(noise::turbulence(q, t.octaves, t.gain), 0.0f, 1.0f);
        case Texture::Kind::Marble: {
            // Stripes across the axis, bent by turbulence.
            const float x = q[t.axis] + t.strength * noise::turbulence(q, t.octaves, t.gain);
            return 0.5f + 0.5f * std::sin(kTwoPi * x);
        }
        case Texture::Kind::Wood: {
            // Rings around the axis, one per unit of radius, wobbled by noise; dark late wood at
            // the end of each ring.
            Vec3 r = q;
            r[t.axis] = 0;
            const float g =
                length(r) + 0.25f * t.strength * noise::fbm(q, t.octaves, t.gain) / octaveNorm(t);
            const float f = fract(g);
            return f * f;
        }
        case Texture::Kind::Image:
            break;
    }
    return 0.0f;
}

Vec3 evalTexture(const Texture& t, const std::vector<TextureImage>& images,
                 const TextureInputs& in) {
    const Vec3 q = in.point / t.scale;
    Texture::Projection projection = t.projection;
    if (projection == Texture::Projection::Grid) {
        if (in.hasUv) return sample2D(t, images, in.u / t.scale, in.v / t.scale);
        projection = Texture::Projection::Triplanar;  // no coordinates here
    }
    if (projection == Texture::Projection::Solid && t.kind == Texture::Kind::Image)
        projection = Texture::Projection::Triplanar;  // an image has no third dimension
    switch (projection) {
        case Texture::Projection::Solid: {
            const float s = proceduralPattern(t, q);
            return t.colors[0] * (1 - s) + t.colors[1] * s;
        }
        case Texture::Projection::Planar: {
            float u, v;
            planarUv(q, t.axis, u, v);
            return sample2D(t, images, u, v);
        }
        default: {
            // Liktor §4.2.2: each plane weighted by how squarely the surface faces it.
            float w[3], total = 0;
            for (int a = 0; a < 3; ++a) {
                w[a] = std::pow(std::fabs(in.normal[a]), t.sharpness);
                total += w[a];
            }
            if (!(total > 0)) {
                w[1] = total = 1;
                w[0] = w[2] = 0;
            }
            Vec3 c(0.0f);
            for (int a = 0; a < 3; ++a) {
                if (w[a] <= 0) continue;
                float u, v;
                planarUv(q, a, u, v);
                c += sample2D(t, images, u, v) * (w[a] / total);
            }
            return c;
        }
    }
}

const char* textureKindNames() { return "checker, noise, turbulence, marble, wood, image"; }

bool parseTextureKind(const std::string& s, Texture::Kind& out) {
    using K = Texture::Kind;
    if (s == "checker") return out = K::Checker, true;
    if (s == "noise") return out = K::Noise, true;
    if (s == "turbulence") return out = K::Turbulence, true;
    if (s == "marble") return out = K::Marble, true;
    if (s == "wood") return out = K::Wood, true;
    if (s == "image") return out = K::Image, true;
    return false;
}

const char* textureProjectionNames() { return "solid, planar, triplanar, grid"; }

bool parseTextureProjection(const std::string& s, Texture::Projection& out) {
    using P = Texture::Projection;
    if (s == "solid") return out = P::Solid, true;
    if (s == "planar") return out = P::Planar, true;
    if (s == "triplanar") return out = P::Triplanar, true;
    if (s == "grid") return out = P::Grid, true;
    return false;
}

}  // namespace sdft
