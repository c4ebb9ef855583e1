// Normals as the gradient of the field by finite differences: grad f ~ sum_i o_i f(p + h o_i),
// central differences over the six axis directions or the tetrahedral estimate over the four
// vertices of a tetrahedron (Keinert et al. 2014 use the latter). Shared by the CPU renderer's
// batched normals and the per-thread device path.
#pragma once

#include "sdftrace/core/macros.h"
#include "sdftrace/field/tape_view.h"
#include "sdftrace/math/vec.h"
#include "sdftrace/render/render_settings.h"

namespace sdft {

SDFT_HOST_DEVICE inline int stencilSize(NormalEstimator e) {
    return e == NormalEstimator::Central ? 6 : 4;
}

// Offset k < stencilSize(e): central (+x, -x, +y, -y, +z, -z); tetrahedral (1, -1, -1),
// (-1, -1, 1), (-1, 1, -1), (1, 1, 1).
SDFT_HOST_DEVICE inline Vec3 stencilOffset(NormalEstimator e, int k) {
    if (e == NormalEstimator::Central) {
        const float s = (k & 1) ? -1.0f : 1.0f;
        const int axis = k >> 1;
        return {axis == 0 ? s : 0.0f, axis == 1 ? s : 0.0f, axis == 2 ? s : 0.0f};
    }
    return {(k == 0 || k == 3) ? 1.0f : -1.0f, (k >= 2) ? 1.0f : -1.0f,
            (k == 1 || k == 3) ? 1.0f : -1.0f};
}

// The stencil's spacing at a primary hit at distance t: half a pixel's footprint there, at least
// `minSpacing` (RenderSettings::normalSpacingMin).
SDFT_HOST_DEVICE inline float primaryNormalSpacing(float t, float pixelRadius, float minSpacing) {
    return maxf(minSpacing, 0.5f * t * pixelRadius);
}

// The unit gradient at p with spacing h; zero where the estimate vanishes.
SDFT_HOST_DEVICE inline Vec3 estimateTapeNormal(const TapeView& tape, Vec3 p, float h,
                                                NormalEstimator e) {
    Vec3 g(0.0f);
    const int n = stencilSize(e);
    for (int k = 0; k < n; ++k) {
        const Vec3 o = stencilOffset(e, k);
        g += o * evalTape(tape, p + o * h);
    }
    return normalize(g);
}

// An estimated normal, or (a crease or a flat extremum: the gradient vanished) the direction back
// towards the viewer rather than a zero vector.
SDFT_HOST_DEVICE inline Vec3 normalOrFacing(Vec3 n, Vec3 rayDirection) {
    return length(n) > 0 ? n : -rayDirection;
}

}  // namespace sdft
