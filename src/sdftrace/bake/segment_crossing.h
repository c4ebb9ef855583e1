// Signed crossings of a segment with a triangle: the jump of the winding number along the segment
// (+1 where it enters through the back of a counter-clockwise triangle, against its normal).
// Used to carry an integer winding number from one grid vertex to the next.
#pragma once

#include <cmath>

#include "sdftrace/math/vec.h"

namespace sdft {

// A triangle prepared for crossing tests: bounds, unit normal and twice the area.
struct CrossingTriangle {
    Vec3 a, b, c;
    Vec3 lo, hi, normal;
    float area2 = 0;

    CrossingTriangle() = default;
    CrossingTriangle(Vec3 a_, Vec3 b_, Vec3 c_) : a(a_), b(b_), c(c_) {
        lo = min(a, min(b, c));
        hi = max(a, max(b, c));
        Vec3 n = cross(b - a, c - a);
        area2 = length(n);
        normal = area2 > 0 ? n / area2 : Vec3(0.0f);
    }
};

// What the segment from p to q does at triangle t.
enum class Crossing { None, Enter, Leave, Undecided };

// `eps` (a length) is the tolerance below which an end on the plane, a segment along the plane or
// a hit near an edge (1e-5 in barycentric terms) is undecided: the caller then evaluates the
// winding number instead of trusting a count.
// Whether the segment's bounds, grown by eps, miss the box [lo, hi].
inline bool segmentMissesBox(Vec3 p, Vec3 q, Vec3 lo, Vec3 hi, float eps) {
    return lo.x > std::fmax(p.x, q.x) + eps || lo.y > std::fmax(p.y, q.y) + eps ||
           lo.z > std::fmax(p.z, q.z) + eps || hi.x < std::fmin(p.x, q.x) - eps ||
           hi.y < std::fmin(p.y, q.y) - eps || hi.z < std::fmin(p.z, q.z) - eps;
}

inline Crossing segmentCrossing(Vec3 p, Vec3 q, const CrossingTriangle& t, float eps) {
    if (t.area2 == 0 || segmentMissesBox(p, q, t.lo, t.hi, eps))
        return Crossing::None;  // a zero-area triangle has no side to cross
    float dp = dot(p - t.a, t.normal), dq = dot(q - t.a, t.normal);
    if ((dp > eps && dq > eps) || (dp < -eps && dq < -eps)) return Crossing::None;
    if (std::fabs(dp - dq) < eps) return Crossing::Undecided;  // along the plane
    Vec3 x = p + (q - p) * (dp / (dp - dq));
    float u = dot(cross(t.b - x, t.c - x), t.normal) / t.area2,
          v = dot(cross(t.c - x, t.a - x), t.normal) / t.area2, w = 1 - u - v;
    float lo = std::fmin(u, std::fmin(v, w));
    if (lo < -1e-5f) return Crossing::None;  // misses the triangle
    // Near an edge or corner, or an end on the surface.
    if (lo < 1e-5f || std::fabs(dp) <= eps || std::fabs(dq) <= eps) return Crossing::Undecided;
    return dp > 0 ? Crossing::Enter : Crossing::Leave;
}

}  // namespace sdft
