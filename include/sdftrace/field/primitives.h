// Distance functions (or distance bounds) of the primitives, in the primitive's own frame, and the
// axis-aligned box of each one's solid. Each takes the point and a pointer to its parameters as
// laid out by its factory in node.h. All are 1-Lipschitz: exact distances unless a comment says
// "bound". primitive_table.h lists them.
#pragma once

#include <cmath>

#include "sdftrace/math/ray.h"
#include "sdftrace/math/vec.h"

namespace sdft::prim {

SDFT_HOST_DEVICE inline float sphere(Vec3 p, const float* k) { return length(p) - k[0]; }

// k: half-size (3).
SDFT_HOST_DEVICE inline float box(Vec3 p, const float* k) {
    Vec3 q = abs(p) - Vec3(k[0], k[1], k[2]);
    return length(max(q, 0.0f)) + minf(maxComponent(q), 0.0f);
}

// k: outer half-size (3), edge radius. Exact.
SDFT_HOST_DEVICE inline float roundBox(Vec3 p, const float* k) {
    float r = k[3];
    Vec3 q = abs(p) - Vec3(k[0] - r, k[1] - r, k[2] - r);
    return length(max(q, 0.0f)) + minf(maxComponent(q), 0.0f) - r;
}

// k: major radius R (ring in the XZ plane), minor radius r.
SDFT_HOST_DEVICE inline float torus(Vec3 p, const float* k) {
    float qx = std::sqrt(p.x * p.x + p.z * p.z) - k[0];
    return std::sqrt(qx * qx + p.y * p.y) - k[1];
}

// k: end a (3), end b (3), radius.
SDFT_HOST_DEVICE inline float capsule(Vec3 p, const float* k) {
    Vec3 a(k[0], k[1], k[2]), b(k[3], k[4], k[5]);
    Vec3 pa = p - a, ba = b - a;
    float bb = dot(ba, ba);
    float h = bb > 0 ? clampf(dot(pa, ba) / bb, 0.0f, 1.0f) : 0.0f;
    return length(pa - ba * h) - k[6];
}

// Capped cylinder along Y. k: radius, half-height.
SDFT_HOST_DEVICE inline float cylinder(Vec3 p, const float* k) {
    float dx = std::sqrt(p.x * p.x + p.z * p.z) - k[0];
    float dy = std::fabs(p.y) - k[1];
    float ox = maxf(dx, 0.0f), oy = maxf(dy, 0.0f);
    return minf(maxf(dx, dy), 0.0f) + std::sqrt(ox * ox + oy * oy);
}

// Solid cone along Y: base disc of radius r at y = -h/2, apex at y = +h/2. k: r, h. Exact: the
// distance in the (radial, y) half-plane to the profile triangle.
SDFT_HOST_DEVICE inline float cone(Vec3 p, const float* k) {
    float r = k[0], h = k[1];
    float wx = std::sqrt(p.x * p.x + p.z * p.z), wy = p.y - 0.5f * h;  // apex at origin
    float qx = r, qy = -h;                                             // apex to base rim
    float s1 = clampf((wx * qx + wy * qy) / (qx * qx + qy * qy), 0.0f, 1.0f);
    float ax = wx - qx * s1, ay = wy - qy * s1;  // to the slanted side
    float s2 = clampf(wx / qx, 0.0f, 1.0f);
    float bx = wx - qx * s2, by = wy - qy;  // to the base disc
    float d = minf(ax * ax + ay * ay, bx * bx + by * by);
    // Inside when below the slanted side and above the base.
    float s = maxf(-(wx * qy - wy * qx), -(wy - qy));
    return std::sqrt(d) * (s > 0 ? 1.0f : -1.0f);
}

// Half-space n.p + d <= 0. k: unit normal (3), offset d.
SDFT_HOST_DEVICE inline float plane(Vec3 p, const float* k) {
    return p.x * k[0] + p.y * k[1] + p.z * k[2] + k[3];
}

// Ellipsoid with semi-axes k[0..2]. Bound, not the distance: the naive (|p/r|-1)·min(r) is a valid
// bound (the map p -> p/r expands distances by at most 1/min r) but far too small far from the
// ellipsoid, so take its max with |p| - max(r), the distance to the circumscribed sphere, which is
// also a lower bound outside and negative inside. The max of two 1-Lipschitz bounds is one too.
SDFT_HOST_DEVICE inline float ellipsoid(Vec3 p, const float* k) {
    Vec3 r(k[0], k[1], k[2]);
    float k0 = length(p / r);
    float scaled = (k0 - 1.0f) * minComponent(r);
    float sphereBound = length(p) - maxComponent(r);
    return maxf(scaled, sphereBound);
}

// Regular octahedron |x|+|y|+|z| = s. Bound (generalized distance to its 4 face-plane pairs).
SDFT_HOST_DEVICE inline float octahedron(Vec3 p, const float* k) {
    Vec3 a = abs(p);
    return (a.x + a.y + a.z - k[0]) * 0.57735027f;
}

// Regular dodecahedron with inradius r, as the generalized distance function of Akleman and Chen
// (Keinert et al. 2014, fig. 11): the max over its 6 face-normal pairs of |n.p| - r. Bound.
SDFT_HOST_DEVICE inline float dodecahedron(Vec3 p, const float* k) {
    const float phi = 1.618033988749895f;
    const float s = 1.0f / std::sqrt(1.0f + phi * phi);  // normalizes (0, 1, phi)
    Vec3 a = abs(p) * s;
    float d = maxf(maxf(a.y + phi * a.z, a.z + phi * a.x), a.x + phi * a.y);
    return d - k[0];
}

// Circumradius of the dodecahedron above per unit inradius (for bounds).
constexpr float kDodecahedronCircumPerInradius = 1.2584f;

// Metaball falloff (Wyvill): w(u) = (1-u^2)^3 for u = r/R < 1. Its steepest slope, max |dw/du|,
// at u = 1/sqrt(5), is 6 u (1-u^2)^2 = 1.71730.
constexpr float kBlobFalloffMaxSlope = 1.7173f;

SDFT_HOST_DEVICE inline float blobFalloff(float u) {
    if (u >= 1.0f) return 0.0f;
    float v = 1.0f - u * u;
    return v * v * v;
}

// Blobs / metaballs (Liktor 2008, fig. 1). k: threshold T, 1/L, count n, then n x (center (3),
// support radius R, strength s). The density sum D(p) = sum s_i w(|p-c_i|/R_i) is Lipschitz with
// L = sum s_i * 1.7173 / R_i, so (T - D)/L is a distance bound (Hart 1996). Taking the max with the
// distance to the nearest support sphere (the surface lies inside the supports) keeps it a bound
// and lets rays far from the blobs take long steps.
SDFT_HOST_DEVICE inline float blobs(Vec3 p, const float* k) {
    float threshold = k[0], invL = k[1];
    int n = static_cast<int>(k[2]);
    const float* b = k + 3;
    float density = 0, support = 1e30f;
    for (int i = 0; i < n; ++i, b += 5) {
        float r = length(p - Vec3(b[0], b[1], b[2]));
        density += b[4] * blobFalloff(r / b[3]);
        support = minf(support, r - b[3]);
    }
    return maxf((threshold - density) * invL, support);
}

// Bounds of each primitive's solid (nodeBounds), in its own frame, from the same parameters.
inline Bounds3 sphereBounds(const float* k) { return {Vec3(-k[0]), Vec3(k[0])}; }
inline Bounds3 boxBounds(const float* k) {
    return {Vec3(-k[0], -k[1], -k[2]), Vec3(k[0], k[1], k[2])};
}
inline Bounds3 roundBoxBounds(const float* k) { return boxBounds(k); }
inline Bounds3 torusBounds(const float* k) {
    Vec3 e(k[0] + k[1], k[1], k[0] + k[1]);
    return {-e, e};
}
inline Bounds3 capsuleBounds(const float* k) {
    Bounds3 b;
    b.include({k[0], k[1], k[2]});
    b.include({k[3], k[4], k[5]});
    return b.expanded(k[6]);
}
inline Bounds3 cylinderBounds(const float* k) {
    return {Vec3(-k[0], -k[1], -k[0]), Vec3(k[0], k[1], k[0])};
}
inline Bounds3 coneBounds(const float* k) {
    return {Vec3(-k[0], -0.5f * k[1], -k[0]), Vec3(k[0], 0.5f * k[1], k[0])};
}
// The solid half-space n.p + d <= 0 is bounded only along an axis-aligned normal.
inline Bounds3 planeBounds(const float* k) {
    Bounds3 b = Bounds3::everything();
    for (int a = 0; a < 3; ++a) {
        Vec3 axis(0.0f);
        axis[a] = 1;
        if (std::fabs(dot(Vec3(k[0], k[1], k[2]), axis)) < 0.999999f) continue;
        if (k[a] > 0)
            b.hi[a] = -k[3] / k[a];
        else
            b.lo[a] = -k[3] / k[a];
    }
    return b;
}
inline Bounds3 ellipsoidBounds(const float* k) { return boxBounds(k); }
inline Bounds3 octahedronBounds(const float* k) { return sphereBounds(k); }
inline Bounds3 dodecahedronBounds(const float* k) {
    const float r = k[0] * kDodecahedronCircumPerInradius;
    return {Vec3(-r), Vec3(r)};
}
// The union of the support spheres.
inline Bounds3 blobsBounds(const float* k) {
    Bounds3 b;
    const int count = static_cast<int>(k[2]);
    for (int i = 0; i < count; ++i) {
        const float* c = &k[3 + 5 * i];
        b = unite(
            b, Bounds3{Vec3(c[0], c[1], c[2]) - Vec3(c[3]), Vec3(c[0], c[1], c[2]) + Vec3(c[3])});
    }
    return b;
}

}  // namespace sdft::prim
