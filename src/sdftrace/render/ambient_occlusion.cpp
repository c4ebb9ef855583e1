#include "sdftrace/render/ambient_occlusion.h"

#include <algorithm>

namespace sdft {

AmbientOcclusionResult ambientOcclusion(const Tape& tape, Vec3 p, Vec3 n,
                                        const AmbientOcclusionOptions& o) {
    AmbientOcclusionResult r;
    const float invL = 1.0f / tape.lipschitz();
    float occlusion = 0, weight = 0.5f;
    for (int i = 1; i <= o.samples; ++i) {
        const float h = static_cast<float>(i) * o.step;
        const float d = tape.eval(p + n * h) * invL;
        occlusion += weight * std::max(0.0f, h - d);
        weight *= 0.5f;
    }
    r.evaluations = o.samples;
    // Normalized by the step so that `strength` does not depend on the scene's scale.
    r.ao = std::clamp(1.0f - o.strength * occlusion / std::max(o.step, 1e-30f), 0.0f, 1.0f);
    return r;
}

}  // namespace sdft
