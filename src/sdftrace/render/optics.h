// Reflection and refraction at a smooth interface (Fresnel, Snell), shared by Whitted rays
// (whitted_pixel.h) and the path tracer (path_pixel.h), on both devices.
#pragma once

#include <cmath>

#include "sdftrace/math/vec.h"

namespace sdft {

// Fresnel reflectance of unpolarized light from a medium of index n1 into n2 at incidence cosine
// cosI (1 under total internal reflection).
SDFT_HOST_DEVICE inline float fresnelDielectric(float cosI, float n1, float n2) {
    cosI = clampf(cosI, 0.0f, 1.0f);
    const float sinT = n1 / n2 * std::sqrt(maxf(0.0f, 1.0f - cosI * cosI));
    if (sinT >= 1.0f) return 1.0f;
    const float cosT = std::sqrt(maxf(0.0f, 1.0f - sinT * sinT));
    const float rs = (n1 * cosI - n2 * cosT) / (n1 * cosI + n2 * cosT);
    const float rp = (n1 * cosT - n2 * cosI) / (n1 * cosT + n2 * cosI);
    return 0.5f * (rs * rs + rp * rp);
}

// Refraction of unit d through unit n (facing against d) with eta = n1 / n2; false under total
// internal reflection.
SDFT_HOST_DEVICE inline bool refract(Vec3 d, Vec3 n, float eta, Vec3& out) {
    const float cosI = -dot(d, n);
    const float k = 1.0f - eta * eta * (1.0f - cosI * cosI);
    if (k < 0) return false;
    out = normalize(d * eta + n * (eta * cosI - std::sqrt(k)));
    return true;
}

// Mirror reflection of d about unit n.
SDFT_HOST_DEVICE inline Vec3 reflect(Vec3 d, Vec3 n) { return d - n * (2.0f * dot(d, n)); }

}  // namespace sdft
