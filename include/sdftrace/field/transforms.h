// Domain transforms shared by the tree reference and the tape evaluators.
#pragma once

#include <cmath>

#include "sdftrace/math/vec.h"

namespace sdft::xform {

// Finite domain repetition. k: cell size (3), copies per side (3), gap (1).
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
// bounds (gap = min_i c_i/2 - extent_i >= 0, checked when the node is built). Taking the min of this
// and the child's value makes mod-style repetition a true distance bound even where a neighbouring
// copy is nearer than the cell's own copy.
SDFT_HOST_DEVICE inline float repeatNeighbourBound(Vec3 p, const float* k) {
    float d = 1e30f;
    for (int i = 0; i < 3; ++i) {
        float c = k[i], n = k[3 + i];
        if (n <= 0) continue;
        float idx = clampf(std::nearbyint(p[i] / c), -n, n);
        float q = p[i] - c * idx;
        if (idx < n) d = std::fmin(d, 0.5f * c - q);
        if (idx > -n) d = std::fmin(d, 0.5f * c + q);
    }
    return d + k[6];
}

}  // namespace sdft::xform
