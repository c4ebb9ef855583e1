// Rays and axis-aligned bounds.
#pragma once

#include <cmath>
#include <limits>

#include "sdftrace/math/vec.h"

namespace sdft {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

// r(t) = origin + t * direction, direction unit length.
struct Ray {
    Vec3 origin;
    Vec3 direction;
    SDFT_HOST_DEVICE Vec3 at(float t) const { return origin + direction * t; }
};

// Axis-aligned box; may be infinite along some axes (a floor plane) or empty (lo > hi).
struct Bounds3 {
    Vec3 lo{kInfinity, kInfinity, kInfinity};
    Vec3 hi{-kInfinity, -kInfinity, -kInfinity};

    static Bounds3 everything() { return {Vec3(-kInfinity), Vec3(kInfinity)}; }
    SDFT_HOST_DEVICE bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
    SDFT_HOST_DEVICE bool finite() const { return isFinite(lo) && isFinite(hi); }
    SDFT_HOST_DEVICE Vec3 extent() const { return hi - lo; }
    SDFT_HOST_DEVICE Vec3 center() const { return (lo + hi) * 0.5f; }
    SDFT_HOST_DEVICE bool contains(Vec3 p) const {
        return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z &&
               p.z <= hi.z;
    }
    Bounds3 expanded(float r) const {
        if (empty()) return *this;
        return {lo - Vec3(r), hi + Vec3(r)};
    }
    void include(Vec3 p) {
        lo = min(lo, p);
        hi = max(hi, p);
    }
};

inline Bounds3 unite(const Bounds3& a, const Bounds3& b) {
    return {min(a.lo, b.lo), max(a.hi, b.hi)};
}
inline Bounds3 intersect(const Bounds3& a, const Bounds3& b) {
    return {max(a.lo, b.lo), min(a.hi, b.hi)};
}

// Slab test. Returns false when the ray misses; otherwise [t0, t1] is the overlap with [tMin,
// tMax]. Handles infinite slabs and zero direction components.
SDFT_HOST_DEVICE inline bool intersectBounds(const Bounds3& b, const Ray& r, float tMin, float tMax,
                                             float& t0, float& t1) {
    t0 = tMin;
    t1 = tMax;
    for (int a = 0; a < 3; ++a) {
        float o = r.origin[a], d = r.direction[a];
        float lo = b.lo[a], hi = b.hi[a];
        if (d == 0.0f) {
            if (o < lo || o > hi) return false;
            continue;
        }
        float inv = 1.0f / d;
        float ta = (lo - o) * inv, tb = (hi - o) * inv;
        if (ta > tb) {
            float tmp = ta;
            ta = tb;
            tb = tmp;
        }
        // NaN arises only for infinite slab limits with o inside; treat as no constraint.
        if (ta == ta) t0 = maxf(t0, ta);
        if (tb == tb) t1 = minf(t1, tb);
        if (t0 > t1) return false;
    }
    return true;
}

}  // namespace sdft
