// A double-precision 3-vector for the bakers' exact geometric predicates (solid angles, closest
// feature regions), where float cancellation would decide a sign. Host-only, header-only.
#pragma once

#include <cmath>

#include "sdftrace/math/vec.h"

namespace sdft {

struct Vec3d {
    double x = 0, y = 0, z = 0;
    double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};

inline Vec3d toDouble(Vec3 v) { return {v.x, v.y, v.z}; }
inline Vec3d operator+(Vec3d a, Vec3d b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3d operator-(Vec3d a, Vec3d b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3d operator*(Vec3d a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline double dot(Vec3d a, Vec3d b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3d cross(Vec3d a, Vec3d b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm(Vec3d a) { return std::sqrt(dot(a, a)); }
// a - b of float points, exact in double.
inline Vec3d difference(Vec3 a, Vec3 b) { return toDouble(a) - toDouble(b); }

}  // namespace sdft
