// Gradient noise (Perlin 2002, "improved noise") and its fractal sum, for displacement and
// procedural textures (Liktor 2008, §5.5.1). Header-only, GPU-ready: the permutation table is a
// constexpr array.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "sdftrace/math/vec.h"

namespace sdft::noise {

namespace detail {
struct PermutationTable {
    uint8_t v[512];
};

// A fixed permutation of 0..255 (Fisher-Yates with a fixed LCG), repeated twice.
constexpr PermutationTable makePermutation() {
    std::array<uint8_t, 256> p{};
    for (int i = 0; i < 256; ++i) p[i] = static_cast<uint8_t>(i);
    uint32_t state = 0x9E3779B9u;
    for (int i = 255; i > 0; --i) {
        state = state * 1664525u + 1013904223u;
        int j = static_cast<int>((state >> 8) % static_cast<uint32_t>(i + 1));
        uint8_t t = p[i];
        p[i] = p[j];
        p[j] = t;
    }
    PermutationTable out{};
    for (int i = 0; i < 512; ++i) out.v[i] = p[i & 255];
    return out;
}
// Host code reads the constexpr table; device code a copy in constant memory.
inline constexpr PermutationTable kPerm = makePermutation();
#if defined(__CUDACC__)
static __constant__ constexpr PermutationTable kPermDevice = makePermutation();
#endif

SDFT_HOST_DEVICE inline const uint8_t* permutation() {
#if defined(__CUDA_ARCH__)
    return kPermDevice.v;
#else
    return kPerm.v;
#endif
}

SDFT_HOST_DEVICE inline float fade(float t) { return t * t * t * (t * (t * 6 - 15) + 10); }
SDFT_HOST_DEVICE inline float lerpf(float a, float b, float t) { return a + (b - a) * t; }
// Dot product with one of the 12 edge-midpoint gradients of the cube.
SDFT_HOST_DEVICE inline float grad(int hash, float x, float y, float z) {
    int h = hash & 15;
    float u = h < 8 ? x : y;
    float v = h < 4 ? y : (h == 12 || h == 14 ? x : z);
    return ((h & 1) ? -u : u) + ((h & 2) ? -v : v);
}
}  // namespace detail

// Perlin improved noise, range about [-1, 1].
SDFT_HOST_DEVICE inline float perlin(Vec3 p) {
    using namespace detail;
    float fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
    int X = static_cast<int>(fx) & 255, Y = static_cast<int>(fy) & 255,
        Z = static_cast<int>(fz) & 255;
    float x = p.x - fx, y = p.y - fy, z = p.z - fz;
    float u = fade(x), v = fade(y), w = fade(z);
    const uint8_t* P = permutation();
    int A = P[X] + Y, AA = P[A] + Z, AB = P[A + 1] + Z;
    int B = P[X + 1] + Y, BA = P[B] + Z, BB = P[B + 1] + Z;
    return lerpf(
        lerpf(lerpf(grad(P[AA], x, y, z), grad(P[BA], x - 1, y, z), u),
              lerpf(grad(P[AB], x, y - 1, z), grad(P[BB], x - 1, y - 1, z), u), v),
        lerpf(lerpf(grad(P[AA + 1], x, y, z - 1), grad(P[BA + 1], x - 1, y, z - 1), u),
              lerpf(grad(P[AB + 1], x, y - 1, z - 1), grad(P[BB + 1], x - 1, y - 1, z - 1), u), v),
        w);
}

// Upper bound of |grad perlin|. The largest gradient found by 2e7 random samples followed by local
// ascent from the worst one is 3.53 (central differences); we keep a 13% margin. noise_test.cpp
// checks the bound on 10^6 samples, and the Lipschitz tests check displaced fields on point pairs.
constexpr float kPerlinLipschitz = 4.0f;

// Fractal sum: sum_i gain^i perlin(p * 2^i), i < octaves.
SDFT_HOST_DEVICE inline float fbm(Vec3 p, int octaves, float gain) {
    float sum = 0, amp = 1;
    for (int i = 0; i < octaves; ++i) {
        sum += amp * perlin(p);
        p = p * 2.0f;
        amp *= gain;
    }
    return sum;
}

// Perlin's turbulence (Perlin 1985): sum_i gain^i |perlin(p * 2^i)|, i < octaves; the sharp
// creases of |noise| at every scale make veins (marble) and flames.
SDFT_HOST_DEVICE inline float turbulence(Vec3 p, int octaves, float gain) {
    float sum = 0, amp = 1;
    for (int i = 0; i < octaves; ++i) {
        sum += amp * std::fabs(perlin(p));
        p = p * 2.0f;
        amp *= gain;
    }
    return sum;
}

// Lipschitz bound of fbm(p * frequency) * amplitude: sum_i amplitude gain^i frequency 2^i L_perlin.
SDFT_HOST_DEVICE inline float fbmLipschitz(float amplitude, float frequency, int octaves,
                                           float gain) {
    float sum = 0, term = amplitude * frequency * kPerlinLipschitz;
    for (int i = 0; i < octaves; ++i, term *= 2 * gain) sum += term;
    return sum;
}

// Largest |fbm| value bound: sum_i gain^i * max|perlin| (max|perlin| <= 1.5 to be safe).
inline float fbmMaxAbs(int octaves, float gain) {
    float sum = 0, amp = 1.5f;
    for (int i = 0; i < octaves; ++i, amp *= gain) sum += amp;
    return sum;
}

}  // namespace sdft::noise
