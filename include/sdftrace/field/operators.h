// CSG operators on distance bounds (Liktor 2008, §2.2) and their smooth variants.
#pragma once

#include <cmath>

#include "sdftrace/math/vec.h"

namespace sdft::ops {

// Polynomial smooth minimum with radius k (Quilez). Returns the blended value and, in `h`, the
// weight of `a` (1 where a dominates). Both partial derivatives lie in [0, 1] and sum to 1, so the
// result is max(La, Lb)-Lipschitz like min itself.
SDFT_HOST_DEVICE inline float smoothMin(float a, float b, float k, float& h) {
    if (k <= 0) {
        h = a <= b ? 1.0f : 0.0f;
        return minf(a, b);
    }
    h = clampf(0.5f + 0.5f * (b - a) / k, 0.0f, 1.0f);
    return b + (a - b) * h - k * h * (1.0f - h);
}

SDFT_HOST_DEVICE inline float smoothMax(float a, float b, float k, float& h) {
    return -smoothMin(-a, -b, k, h);
}

}  // namespace sdft::ops
