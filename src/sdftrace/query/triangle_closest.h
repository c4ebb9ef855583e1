// The closest point of a triangle to a point in double precision, with its barycentric coordinates
// and the feature it lies on (a vertex, an edge or the face): Ericson, Real-Time Collision
// Detection, §5.1.5, whose Voronoi-region tests name the feature; a zero-area triangle answers
// with the nearest of its edges. The feature picks the angle-weighted pseudonormal of the sign
// test (Baerentzen and Aanaes 2005).
#pragma once

#include <cmath>

#include "sdftrace/math/vec3d.h"

namespace sdft {

struct TriangleClosest {
    Vec3d point;
    double bary[3] = {1, 0, 0};  // point = a bary[0] + b bary[1] + c bary[2]
    // 0, 1, 2: vertex a, b, c; 3, 4, 5: edge ab, bc, ca; 6: the face.
    int feature = 0;
};

inline constexpr int kFeatureFace = 6;

// On segment (corner e, corner e+1) of the triangle, as a TriangleClosest.
inline TriangleClosest closestOnTriangleEdge(Vec3d p, const Vec3d corners[3], int e) {
    const Vec3d a = corners[e], ab = corners[(e + 1) % 3] - a;
    const double len2 = dot(ab, ab);
    const double s = len2 > 0 ? std::fmin(std::fmax(dot(p - a, ab) / len2, 0.0), 1.0) : 0.0;
    TriangleClosest r;
    r.point = a + ab * s;
    r.bary[0] = r.bary[1] = r.bary[2] = 0;
    r.bary[e] = 1 - s;
    r.bary[(e + 1) % 3] = s;
    r.feature = s <= 0 ? e : s >= 1 ? (e + 1) % 3 : 3 + e;
    return r;
}

inline TriangleClosest closestOnTriangle(Vec3d p, Vec3d a, Vec3d b, Vec3d c) {
    TriangleClosest r;
    auto vertex = [&](int i, Vec3d v) {
        r.point = v;
        r.bary[0] = r.bary[1] = r.bary[2] = 0;
        r.bary[i] = 1;
        r.feature = i;
        return r;
    };
    auto edge = [&](int i, int j, Vec3d from, Vec3d to, double s) {
        r.point = from + (to - from) * s;
        r.bary[0] = r.bary[1] = r.bary[2] = 0;
        r.bary[i] = 1 - s;
        r.bary[j] = s;
        r.feature = 3 + (i == 2 ? 2 : i);
        return r;
    };
    const Vec3d ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return vertex(0, a);
    const Vec3d bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return vertex(1, b);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return edge(0, 1, a, b, d1 / (d1 - d3));
    const Vec3d cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return vertex(2, c);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return edge(2, 0, c, a, 1 - d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return edge(1, 2, b, c, (d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const double sum = va + vb + vc;
    if (!(std::fabs(sum) > 0) || !std::isfinite(sum)) {  // zero area: the nearest edge
        const Vec3d corners[3] = {a, b, c};
        TriangleClosest best = closestOnTriangleEdge(p, corners, 0);
        for (int e = 1; e < 3; ++e) {
            const TriangleClosest t = closestOnTriangleEdge(p, corners, e);
            if (norm(p - t.point) < norm(p - best.point)) best = t;
        }
        return best;
    }
    const double v = vb / sum, w = vc / sum;
    r.point = a + ab * v + ac * w;
    r.bary[0] = 1 - v - w;
    r.bary[1] = v;
    r.bary[2] = w;
    r.feature = kFeatureFace;
    return r;
}

}  // namespace sdft
