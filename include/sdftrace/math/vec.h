// Small fixed-size vectors. Header-only and GPU-ready (no allocation, no exceptions).
#pragma once

#include <cmath>

#include "sdftrace/core/macros.h"

namespace sdft {

// The largest magnitude of a number user input may give geometry (scene files, flags, mesh
// coordinates): float keeps about 7 digits, and squared and multiplied distances must stay finite.
inline constexpr float kMaxCoordinate = 1e9f;

// pi, the one definition every module uses.
inline constexpr float kPi = 3.14159265358979f;
SDFT_HOST_DEVICE constexpr float radians(float degrees) { return degrees * kPi / 180.0f; }

// min/max that compile to one instruction (std::fmin/fmax are libm calls for their NaN rules).
// Hot-path values are never NaN.
SDFT_HOST_DEVICE constexpr float minf(float a, float b) { return a < b ? a : b; }
SDFT_HOST_DEVICE constexpr float maxf(float a, float b) { return a > b ? a : b; }

struct Vec2 {
    float x = 0, y = 0;
};

struct Vec3 {
    float x = 0, y = 0, z = 0;

    constexpr Vec3() = default;
    SDFT_HOST_DEVICE constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
    SDFT_HOST_DEVICE constexpr explicit Vec3(float s) : x(s), y(s), z(s) {}

    SDFT_HOST_DEVICE float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    SDFT_HOST_DEVICE float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
};

SDFT_HOST_DEVICE inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
SDFT_HOST_DEVICE inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
SDFT_HOST_DEVICE inline Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
SDFT_HOST_DEVICE inline Vec3 operator*(Vec3 a, Vec3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
SDFT_HOST_DEVICE inline Vec3 operator/(Vec3 a, Vec3 b) { return {a.x / b.x, a.y / b.y, a.z / b.z}; }
SDFT_HOST_DEVICE inline Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
SDFT_HOST_DEVICE inline Vec3 operator*(float s, Vec3 a) { return a * s; }
SDFT_HOST_DEVICE inline Vec3 operator/(Vec3 a, float s) { return a * (1.0f / s); }
SDFT_HOST_DEVICE inline Vec3& operator+=(Vec3& a, Vec3 b) { return a = a + b; }
SDFT_HOST_DEVICE inline Vec3& operator-=(Vec3& a, Vec3 b) { return a = a - b; }
SDFT_HOST_DEVICE inline Vec3& operator*=(Vec3& a, float s) { return a = a * s; }

SDFT_HOST_DEVICE inline float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
SDFT_HOST_DEVICE inline Vec3 cross(Vec3 a, Vec3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
SDFT_HOST_DEVICE inline float length(Vec3 a) { return std::sqrt(dot(a, a)); }
SDFT_HOST_DEVICE inline Vec3 normalize(Vec3 a) {
    float len = length(a);
    return len > 0 ? a / len : Vec3(0, 0, 0);
}
SDFT_HOST_DEVICE inline Vec3 abs(Vec3 a) {
    return {std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)};
}
SDFT_HOST_DEVICE inline Vec3 min(Vec3 a, Vec3 b) {
    return {minf(a.x, b.x), minf(a.y, b.y), minf(a.z, b.z)};
}
SDFT_HOST_DEVICE inline Vec3 max(Vec3 a, Vec3 b) {
    return {maxf(a.x, b.x), maxf(a.y, b.y), maxf(a.z, b.z)};
}
SDFT_HOST_DEVICE inline Vec3 max(Vec3 a, float s) { return max(a, Vec3(s)); }
SDFT_HOST_DEVICE inline float minComponent(Vec3 a) { return minf(a.x, minf(a.y, a.z)); }
SDFT_HOST_DEVICE inline float maxComponent(Vec3 a) { return maxf(a.x, maxf(a.y, a.z)); }
SDFT_HOST_DEVICE inline Vec3 lerp(Vec3 a, Vec3 b, float t) { return a + (b - a) * t; }
SDFT_HOST_DEVICE inline bool isFinite(Vec3 a) {
    return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}
SDFT_HOST_DEVICE inline float clampf(float v, float lo, float hi) { return minf(maxf(v, lo), hi); }

// Row-major 3x3 matrix (rotations).
struct Mat3 {
    float m[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

    SDFT_HOST_DEVICE Vec3 operator*(Vec3 v) const {
        return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
                m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
    }
    SDFT_HOST_DEVICE Mat3 transposed() const {
        Mat3 t;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) t.m[i][j] = m[j][i];
        return t;
    }
};

// Rotation by `degrees` about the (unit) `axis`, Rodrigues' formula.
inline Mat3 rotationAxisAngle(Vec3 axis, float degrees) {
    Vec3 a = normalize(axis);
    float rad = radians(degrees);
    float c = std::cos(rad), s = std::sin(rad), t = 1 - c;
    Mat3 r;
    r.m[0][0] = t * a.x * a.x + c;
    r.m[0][1] = t * a.x * a.y - s * a.z;
    r.m[0][2] = t * a.x * a.z + s * a.y;
    r.m[1][0] = t * a.x * a.y + s * a.z;
    r.m[1][1] = t * a.y * a.y + c;
    r.m[1][2] = t * a.y * a.z - s * a.x;
    r.m[2][0] = t * a.x * a.z - s * a.y;
    r.m[2][1] = t * a.y * a.z + s * a.x;
    r.m[2][2] = t * a.z * a.z + c;
    return r;
}

}  // namespace sdft
