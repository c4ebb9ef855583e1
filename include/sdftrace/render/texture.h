// Textures as material inputs (Liktor 2008, §4.2 and §5.5). An implicit surface has no vertices
// to carry (u, v), so a colour comes from
//  - a solid (3D) procedural texture at the point (§4.2.1, §5.5.1): checker, Perlin noise with
//    octaves, turbulence, marble, wood;
//  - a 2D texture (an image, or a procedural one on the plane) projected onto the surface
//    (§4.2.2): planar along an axis, tri-planar blended by the normal, or through texture
//    coordinates precomputed into a grid by tracing particles along the gradient to a helper
//    surface (§5.5.2; bake/texture_coords.h).
// Points and normals are in the frame of the object that carries the material (inside its own
// translate, rotate and scale), so textures move with their objects.
// The lookup is header-only and plain data (TextureParams, ImageView): the CPU's materialAt and
// the per-pixel path a GPU thread runs (direct_pixel.h) evaluate the same functions.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "sdftrace/core/macros.h"
#include "sdftrace/field/material_blend.h"
#include "sdftrace/field/noise.h"
#include "sdftrace/math/vec.h"

namespace sdft {

// An image's pixels where a lookup reads them (host or device memory): linear RGB, rows top to
// bottom.
struct ImageView {
    const float* rgb = nullptr;
    int width = 0, height = 0;
    // Bilinear, repeating; v = 0 is the bottom row, v = 1 the top.
    SDFT_HOST_DEVICE Vec3 sample(float u, float v) const;
};

// A decoded image.
struct TextureImage {
    std::string path;
    int width = 0, height = 0;
    std::vector<float> rgb;
    ImageView view() const { return {rgb.data(), width, height}; }
    Vec3 sample(float u, float v) const { return view().sample(u, v); }
};

// A texture's parameters: plain data, copied to a device as they are.
struct TextureParams {
    enum class Kind { Checker, Noise, Turbulence, Marble, Wood, Image };
    enum class Projection {
        Solid,      // procedural at the 3D point
        Planar,     // along `axis` (0 x, 1 y, 2 z): the other two coordinates
        Triplanar,  // the three planar projections weighted by |n_axis|^sharpness
        Grid,       // (u, v) stored in the object's grid (Liktor §5.5.2); tri-planar elsewhere
    };
    Kind kind = Kind::Checker;
    Projection projection = Projection::Solid;
    Vec3 colors[2] = {Vec3(0.1f), Vec3(0.9f)};  // procedural: the two ends of the pattern
    float scale = 1;      // scene units per pattern unit (per image repeat); grid: (u, v) units
    int octaves = 4;      // noise, turbulence, marble, wood
    float gain = 0.5f;    // amplitude ratio of successive octaves (frequency doubles)
    float strength = 1;   // marble and wood: weight of the turbulence that bends the pattern
    int axis = 1;         // planar projection, marble's stripes and wood's rings
    float sharpness = 4;  // tri-planar blend exponent
    int image = -1;       // index into the scene's images
};

// A texture of a scene: its parameters and the name materials refer to it by.
struct Texture : TextureParams {
    std::string name;
};

// What a texture is looked up with.
struct TextureInputs {
    Vec3 point{0, 0, 0};   // in the material's object frame
    Vec3 normal{0, 1, 0};  // unit, same frame
    bool hasUv = false;
    float u = 0, v = 0;  // from a texture-coordinate grid
};

// A scene's images as a lookup reads them: image i, or an empty view (black) where there is none.
struct ImageTable {
    const ImageView* images = nullptr;
    int count = 0;
    SDFT_HOST_DEVICE ImageView operator[](int i) const {
        return i >= 0 && i < count ? images[i] : ImageView{};
    }
};

// The scalar pattern of a procedural texture in [0, 1] at q (already divided by the scale).
SDFT_HOST_DEVICE float proceduralPattern(const TextureParams& t, Vec3 q);

// The colour of `t` at `in`.
SDFT_HOST_DEVICE Vec3 evalTexture(const TextureParams& t, const ImageTable& images,
                                  const TextureInputs& in);
// The same over a scene's decoded images.
Vec3 evalTexture(const TextureParams& t, const std::vector<TextureImage>& images,
                 const TextureInputs& in);

// Whether `t` reads the surface normal: projected and image textures (solid procedural ones
// do not).
SDFT_HOST_DEVICE inline bool textureNeedsNormal(const TextureParams& t) {
    return t.projection != TextureParams::Projection::Solid || t.kind == TextureParams::Kind::Image;
}

// How far from the world point p a material blend is evaluated a second time to find the normal
// in an object's frame (textureInputs).
SDFT_HOST_DEVICE inline float textureNormalStep(Vec3 p) { return 1e-3f * fmaxf(1.0f, length(p)); }

// The inputs of entry i of the material blend b at a surface point. `offset` (null where the
// texture needs no normal) is the blend a textureNormalStep along the world normal: the normal
// in the object's frame is where that frame maps the step. Exact under rotation and uniform
// scale; a non-uniform scale tilts it toward the squashed axis (only the projection's blend
// weights see that).
SDFT_HOST_DEVICE inline TextureInputs textureInputs(const MaterialBlend& b, int i,
                                                    const MaterialBlend* offset) {
    TextureInputs in;
    in.point = b.local[i];
    in.hasUv = b.hasUv[i];
    in.u = b.u[i];
    in.v = b.v[i];
    if (offset) {
        for (int j = 0; j < offset->count; ++j)
            if (offset->id[j] == b.id[i] && length(offset->local[j] - b.local[i]) > 0)
                in.normal = normalize(offset->local[j] - b.local[i]);
    }
    return in;
}

// Names as in scene files.
const char* textureKindNames();  // "checker, noise, turbulence, marble, wood, image"
bool parseTextureKind(const std::string& s, Texture::Kind& out);
const char* textureProjectionNames();  // "solid, planar, triplanar, grid"
bool parseTextureProjection(const std::string& s, Texture::Projection& out);

namespace texture_detail {

SDFT_HOST_DEVICE inline float fract(float x) { return x - floorf(x); }

// Sum of the octave amplitudes: fbm / norm and turbulence / norm stay within about [-1, 1].
SDFT_HOST_DEVICE inline float octaveNorm(const TextureParams& t) {
    float sum = 0, amp = 1;
    for (int i = 0; i < t.octaves; ++i, amp *= t.gain) sum += amp;
    return fmaxf(sum, 1e-6f);
}

// The two coordinates a planar projection along `axis` keeps: x -> (z, y), y -> (x, z),
// z -> (x, y).
SDFT_HOST_DEVICE inline void planarUv(Vec3 q, int axis, float& u, float& v) {
    if (axis == 0) {
        u = q.z, v = q.y;
    } else if (axis == 1) {
        u = q.x, v = q.z;
    } else {
        u = q.x, v = q.y;
    }
}

// A 2D texture at (u, v): the image, or the procedural pattern on the plane z = 0.
SDFT_HOST_DEVICE inline Vec3 sample2D(const TextureParams& t, const ImageTable& images, float u,
                                      float v) {
    if (t.kind == TextureParams::Kind::Image) return images[t.image].sample(u, v);
    const float s = proceduralPattern(t, Vec3(u, v, 0.0f));
    return t.colors[0] * (1 - s) + t.colors[1] * s;
}

SDFT_HOST_DEVICE inline float clamp01(float x) { return fminf(fmaxf(x, 0.0f), 1.0f); }

}  // namespace texture_detail

SDFT_HOST_DEVICE inline Vec3 ImageView::sample(float u, float v) const {
    if (width <= 0 || height <= 0 || !rgb) return Vec3(0.0f);
    // Texel centres at (i + 0.5) / width; v up.
    const float x = texture_detail::fract(u) * width - 0.5f;
    const float y = (1 - texture_detail::fract(v)) * height - 0.5f;
    const float fx = floorf(x), fy = floorf(y);
    const float ax = x - fx, ay = y - fy;
    Vec3 c(0.0f);
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            const int i = ((static_cast<int>(fx) + dx) % width + width) % width;
            const int j = ((static_cast<int>(fy) + dy) % height + height) % height;
            const size_t p = 3 * (static_cast<size_t>(j) * width + i);
            const float w = (dx ? ax : 1 - ax) * (dy ? ay : 1 - ay);
            c += Vec3(rgb[p], rgb[p + 1], rgb[p + 2]) * w;
        }
    return c;
}

// Liktor 2008, §5.5.1 (after Perlin 1985 and Watt & Watt 1992, ch. 7): octaves double the
// frequency and scale the amplitude by `gain`.
SDFT_HOST_DEVICE inline float proceduralPattern(const TextureParams& t, Vec3 q) {
    using K = TextureParams::Kind;
    switch (t.kind) {
        case K::Checker: {
            const int s = static_cast<int>(floorf(q.x) + floorf(q.y) + floorf(q.z));
            return static_cast<float>(s & 1);
        }
        // fbm sums to about [-1, 1] and turbulence to about [0, 1] for the default gain (octave
        // amplitudes 1, 1/2, ... times Perlin's typical |value| of about 0.5).
        case K::Noise:
            return texture_detail::clamp01(0.5f + 0.5f * noise::fbm(q, t.octaves, t.gain));
        case K::Turbulence:
            return texture_detail::clamp01(noise::turbulence(q, t.octaves, t.gain));
        case K::Marble: {
            // Stripes across the axis, bent by turbulence.
            const float x = q[t.axis] + t.strength * noise::turbulence(q, t.octaves, t.gain);
            return 0.5f + 0.5f * sinf(6.28318531f * x);
        }
        case K::Wood: {
            // Rings around the axis, one per unit of radius, wobbled by noise; dark late wood at
            // the end of each ring.
            Vec3 r = q;
            r[t.axis] = 0;
            const float g = length(r) + 0.25f * t.strength * noise::fbm(q, t.octaves, t.gain) /
                                            texture_detail::octaveNorm(t);
            const float f = texture_detail::fract(g);
            return f * f;
        }
        case K::Image:
            break;
    }
    return 0.0f;
}

SDFT_HOST_DEVICE inline Vec3 evalTexture(const TextureParams& t, const ImageTable& images,
                                         const TextureInputs& in) {
    using P = TextureParams::Projection;
    const Vec3 q = in.point / t.scale;
    P projection = t.projection;
    if (projection == P::Grid) {
        if (in.hasUv) return texture_detail::sample2D(t, images, in.u / t.scale, in.v / t.scale);
        projection = P::Triplanar;  // no coordinates here
    }
    if (projection == P::Solid && t.kind == TextureParams::Kind::Image)
        projection = P::Triplanar;  // an image has no third dimension
    if (projection == P::Solid) {
        const float s = proceduralPattern(t, q);
        return t.colors[0] * (1 - s) + t.colors[1] * s;
    }
    if (projection == P::Planar) {
        float u, v;
        texture_detail::planarUv(q, t.axis, u, v);
        return texture_detail::sample2D(t, images, u, v);
    }
    // Liktor §4.2.2: each plane weighted by how squarely the surface faces it.
    float w[3], total = 0;
    for (int a = 0; a < 3; ++a) {
        w[a] = powf(fabsf(in.normal[a]), t.sharpness);
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
        texture_detail::planarUv(q, a, u, v);
        c += texture_detail::sample2D(t, images, u, v) * (w[a] / total);
    }
    return c;
}

}  // namespace sdft
