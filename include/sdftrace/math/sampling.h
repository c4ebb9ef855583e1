// Random numbers for rendering: a counter-based hash (PCG, O'Neill 2014) so that a pixel's
// sample k is the same whatever thread renders it, and the unit-square warps the samplers use.
// GPU-ready.
#pragma once

#include <cmath>
#include <cstdint>

#include "sdftrace/core/macros.h"
#include "sdftrace/math/vec.h"

namespace sdft {

// PCG-RXS-M-XS 32-bit output of one LCG step: a good hash of a 32-bit counter.
SDFT_HOST_DEVICE inline uint32_t pcgHash(uint32_t v) {
    uint32_t state = v * 747796405u + 2891336453u;
    uint32_t word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// A stream of uniform floats in [0, 1) seeded by a pixel, a frame and a purpose.
class Rng {
  public:
    SDFT_HOST_DEVICE Rng(uint32_t a, uint32_t b = 0, uint32_t c = 0)
        : m_state(pcgHash(a ^ pcgHash(b ^ pcgHash(c)))) {}
    SDFT_HOST_DEVICE uint32_t next() {
        m_state = m_state * 747796405u + 2891336453u;
        uint32_t word = ((m_state >> ((m_state >> 28u) + 4u)) ^ m_state) * 277803737u;
        return (word >> 22u) ^ word;
    }
    // 24 random bits: exactly representable, strictly below 1.
    SDFT_HOST_DEVICE float uniform() { return static_cast<float>(next() >> 8) * 0x1p-24f; }

  private:
    uint32_t m_state;
};

// The radical inverse of i in `base` (the Halton sequence's coordinate), in [0, 1).
SDFT_HOST_DEVICE inline float radicalInverse(uint32_t i, uint32_t base) {
    float f = 1, r = 0;
    while (i > 0) {
        f /= static_cast<float>(base);
        r += f * static_cast<float>(i % base);
        i /= base;
    }
    return r;
}

// Point i of the Halton (2, 3) sequence shifted by (r1, r2) modulo 1 (a Cranley-Patterson
// rotation, so that each pixel has its own well-spread sequence).
SDFT_HOST_DEVICE inline void rotatedHalton(uint32_t i, float r1, float r2, float& u1, float& u2) {
    u1 = radicalInverse(i, 2) + r1;
    u2 = radicalInverse(i, 3) + r2;
    u1 -= u1 >= 1.0f ? 1.0f : 0.0f;
    u2 -= u2 >= 1.0f ? 1.0f : 0.0f;
}

// An orthonormal basis around unit n (Duff et al. 2017, branchless).
SDFT_HOST_DEVICE inline void orthonormalBasis(Vec3 n, Vec3& t, Vec3& b) {
    float sign = std::copysign(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    t = Vec3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    b = Vec3(c, sign + n.y * n.y * a, -n.y);
}

// A direction uniform in solid angle within the cone of half-angle acos(cosMax) around unit `axis`.
SDFT_HOST_DEVICE inline Vec3 sampleCone(Vec3 axis, float cosMax, float u1, float u2) {
    float cosT = 1.0f - u1 * (1.0f - cosMax);
    float sinT = std::sqrt(std::fmax(0.0f, 1.0f - cosT * cosT));
    float phi = 6.2831853f * u2;
    Vec3 t, b;
    orthonormalBasis(axis, t, b);
    return t * (sinT * std::cos(phi)) + b * (sinT * std::sin(phi)) + axis * cosT;
}

// A direction with density cos(theta) / pi about unit n (Malley's method).
SDFT_HOST_DEVICE inline Vec3 sampleCosine(Vec3 n, float u1, float u2) {
    float r = std::sqrt(u1), phi = 6.2831853f * u2;
    Vec3 t, b;
    orthonormalBasis(n, t, b);
    return t * (r * std::cos(phi)) + b * (r * std::sin(phi)) +
           n * std::sqrt(std::fmax(0.0f, 1.0f - u1));
}

}  // namespace sdft
