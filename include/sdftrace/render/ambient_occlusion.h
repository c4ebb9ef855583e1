// SDF ambient occlusion: a few distance samples along the normal (Evans, "Fast approximations for
// global illumination on dynamic scenes", SIGGRAPH 2006 course; Quilez). At p + n i·step the
// distance to the scene would be i·step over an open plane; what it falls short by is occlusion,
// weighted 1/2^i so near samples count most:
//   ao = clamp(1 - strength · sum_i (i·step - f(p + n i·step)) / 2^i, 0, 1).
#pragma once

#include "sdftrace/core/macros.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/field/tape_view.h"

namespace sdft {

struct AmbientOcclusionOptions {
    int samples = 5;
    float step = 0.1f;  // scene units between samples
    float strength = 1.0f;
};

struct AmbientOcclusionResult {
    float ao = 1;  // 1: unoccluded
    int evaluations = 0;
};

// By a tape's scalar evaluator: a device thread's, and the CPU's ambientOcclusion below.
SDFT_HOST_DEVICE inline AmbientOcclusionResult ambientOcclusionTape(
    const TapeView& field, Vec3 p, Vec3 n, const AmbientOcclusionOptions& o) {
    AmbientOcclusionResult r;
    const float invL = 1.0f / field.lipschitz;
    float occlusion = 0, weight = 0.5f;
    for (int i = 1; i <= o.samples; ++i) {
        const float h = static_cast<float>(i) * o.step;
        const float d = evalTape(field, p + n * h) * invL;
        occlusion += weight * maxf(0.0f, h - d);
        weight *= 0.5f;
    }
    r.evaluations = o.samples;
    // Normalized by the step so that `strength` does not depend on the scene's scale.
    const float ao = 1.0f - o.strength * occlusion / maxf(o.step, 1e-30f);
    r.ao = clampf(ao, 0.0f, 1.0f);
    return r;
}

AmbientOcclusionResult ambientOcclusion(const Tape& tape, Vec3 p, Vec3 n,
                                        const AmbientOcclusionOptions& options);

}  // namespace sdft
