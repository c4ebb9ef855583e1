// SDF ambient occlusion: a few distance samples along the normal (Evans, "Fast approximations for
// global illumination on dynamic scenes", SIGGRAPH 2006 course; Quilez). At p + n i·step the
// distance to the scene would be i·step over an open plane; what it falls short by is occlusion,
// weighted 1/2^i so near samples count most:
//   ao = clamp(1 - strength · sum_i (i·step - f(p + n i·step)) / 2^i, 0, 1).
#pragma once

#include "sdftrace/field/tape.h"

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

AmbientOcclusionResult ambientOcclusion(const Tape& tape, Vec3 p, Vec3 n,
                                        const AmbientOcclusionOptions& options);

}  // namespace sdft
