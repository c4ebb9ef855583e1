#include "sdftrace/render/soft_shadow.h"

#include <algorithm>
#include <cmath>

namespace sdft {

namespace {

// The visible share of a disk whose edge-to-centre offset is s radii (s = -1: hidden, 1: clear).
float diskShare(float s) {
    s = std::clamp(s, -1.0f, 1.0f);
    return 0.5f + (s * std::sqrt(1.0f - s * s) + std::asin(s)) / 3.14159265f;
}

}  // namespace

// RTSDF §2.4-2.5 (see the header).
SoftShadowResult softShadow(const Tape& tape, Vec3 origin, Vec3 dir, float tMin, float tMax,
                            float tanRadius, const SoftShadowOptions& o, float jitter01) {
    SoftShadowResult r;
    if (!(tanRadius < INFINITY)) return r;  // inside the light: nothing can cover all of it
    const float invL = 1.0f / tape.lipschitz();
    const float k = tanRadius > 0 ? 1.0f / tanRadius : 0.0f;
    const bool centered = o.centered && k > 0;
    float t = tMin + (o.jitter && o.maxStep > 0 ? jitter01 * o.maxStep : 0.0f);
    float prev = INFINITY;
    float s = 1.0f;  // the closest approach in light radii (RTSDF: the visibility itself)
    for (int i = 0; i < o.maxSteps && t < tMax; ++i) {
        const float h = tape.eval(origin + dir * t) * invL - o.bias;
        ++r.evaluations;
        if (!centered && h < o.epsilon) {
            s = 0;
            break;
        }
        if (k > 0) {
            float clearance;
            if (o.triangulate && prev < INFINITY && h > 0 && prev > 0) {
                // E: where the spheres of the two samples come closest to the ray.
                const float y = h * h / (2.0f * prev);
                const float d = std::sqrt(std::fmax(0.0f, h * h - y * y));
                clearance = d / std::fmax(t - y, 1e-12f);
            } else {
                clearance = h / std::fmax(t, 1e-12f);
            }
            s = std::min(s, k * clearance);
            if (centered && s <= -1.0f) break;
        } else if (h < o.epsilon) {
            s = centered ? -1.0f : 0.0f;
            break;
        }
        prev = h;
        // Inside an occluder (centered) the distance is negative: step by its size, at least a
        // small fraction of t so the march gets through.
        float step = std::fabs(h);
        if (centered) step = std::fmax(step, std::fmax(o.epsilon, 2e-3f * t));
        t += o.maxStep > 0 ? std::min(step, o.maxStep) : step;
    }
    r.visibility = centered ? diskShare(s) : std::clamp(s, 0.0f, 1.0f);
    return r;
}

}  // namespace sdft
