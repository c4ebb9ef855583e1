// Domain transforms shared by the tree reference and the tape evaluators.
#pragma once

#include <cmath>

#include "sdftrace/math/vec.h"

namespace sdft::xform {

// Finite domain repetition. k: cell size (3), copies per side (3), gap (1), bounds of the whole
// array lo (3), hi (3).
// Maps p into the frame of its nearest copy (indices clamped to [-n, n]).
SDFT_HOST_DEVICE inline Vec3 repeatPoint(Vec3 p, const float* k) {
    Vec3 q = p;
    for (int i = 0; i < 3; ++i) {
        float c = k[i], n = k[3 + i];
        if (n <= 0) continue;
        float idx = clampf(std::nearbyint(p[i] / c), -n, n);
        q[i] = p[i] - c * idx;
    }
    return q;
}

// Lower bound of the distance from p to the copies in *other* cells: the distance to the walls of
// p's cell that have a neighbour behind them, plus the gap between a cell wall and the child's
// bounds (gap = min_i c_i/2 - extent_i >= 0, checked when the node is built). Taking the min of
// this and the child's value makes mod-style repetition a true distance bound even where a
// neighbouring copy is nearer than the cell's own copy. Every copy also lies in the array's bounds,
// so the distance to those bounds is a second lower bound; the max of the two is tight outside the
// array.
SDFT_HOST_DEVICE inline float boxDistance(Vec3 p, const float* k);
SDFT_HOST_DEVICE inline float repeatNeighbourBound(Vec3 p, const float* k) {
    float d = 1e30f;
    for (int i = 0; i < 3; ++i) {
        float c = k[i], n = k[3 + i];
        if (n <= 0) continue;
        float idx = clampf(std::nearbyint(p[i] / c), -n, n);
        float q = p[i] - c * idx;
        if (idx < n) d = minf(d, 0.5f * c - q);
        if (idx > -n) d = minf(d, 0.5f * c + q);
    }
    return maxf(d + k[6], boxDistance(p, k + 7));
}

// Signed distance from p to the box k[0..2] (lo) - k[3..5] (hi): negative inside.
SDFT_HOST_DEVICE inline float signedBoxDistance(Vec3 p, const float* k) {
    const Vec3 lo(k[0], k[1], k[2]), hi(k[3], k[4], k[5]);
    const Vec3 q = max(lo - p, p - hi);
    return length(max(q, 0.0f)) + minf(maxComponent(q), 0.0f);
}

// A repeated child whose value is not at least the distance to its bounds (a distance bound such
// as the ellipsoid's, a displacement, an intersection) is raised to the signed distance to its
// bounds box: still a lower bound of the distance to its surface with the same sign (the surface
// lies in the box), still Lipschitz (the max of two), and now at least the gap at the cell walls,
// so the repetition's min with the neighbour bound stays continuous there.
SDFT_HOST_DEVICE inline float floorByBounds(float value, Vec3 p, const float* k) {
    return maxf(value, signedBoxDistance(p, k));
}

// Distance from p to the box k[0..2] (lo) - k[3..5] (hi); 0 inside.
SDFT_HOST_DEVICE inline float boxDistance(Vec3 p, const float* k) {
    float dx = maxf(maxf(k[0] - p.x, p.x - k[3]), 0.0f);
    float dy = maxf(maxf(k[1] - p.y, p.y - k[4]), 0.0f);
    float dz = maxf(maxf(k[2] - p.z, p.z - k[5]), 0.0f);
    return std::sqrt(dx * dx + dy * dy + dz * dz);
}

}  // namespace sdft::xform
