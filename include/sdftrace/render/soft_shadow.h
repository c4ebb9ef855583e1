// SDF soft shadows: one march from a surface point towards the light's centre, estimating the
// penumbra from how closely the ray passes the scene (RTSDF §2.4-2.5, after Quilez's k·h/t).
//  - k·h/t: h/t is the tangent of the angle by which the ray clears the closest surface at t; the
//    light is taken as fully visible once that exceeds its angular radius (k = 1 / tan radius).
//    As RTSDF fig. 16 notes, this widens penumbrae outwards: the umbra is the hard shadow.
//  - Aaltonen's triangulation (RTSDF fig. 8): from two consecutive samples (distances h_prev,
//    h at t), the closest approach between them is estimated at E, y = h² / (2 h_prev) back along
//    the ray, with clearance d = sqrt(h² - y²): less banding than h/t.
//  - A maximum step (RTSDF §2.5.2) so that neighbouring pixels take similar samples, and a
//  per-pixel
//    jitter of the start within one step against the step pattern (removed by accumulation).
//  - A bias subtracted from the distance (§2.5.3): thickens thin surfaces against holes in the
//    umbra of a coarse grid.
//  - `centered` (ours, default): the march goes on through occluders with negative distances, so
//    the closest approach s (in units of the light's angular radius) runs from -1 (the light
//    hidden) to +1, and the visibility is the share of a disk cut by a straight edge at s,
//    1/2 + (s sqrt(1 - s²) + asin s) / pi. The penumbra then straddles the hard shadow's edge as
//    the ground truth's does, instead of widening outwards.
#pragma once

#include <cmath>
#include <vector>

#include "sdftrace/core/macros.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/field/tape_view.h"

namespace sdft {

struct SoftShadowOptions {
    bool triangulate = true;  // Aaltonen's estimate; false: k·h/t
    float maxStep = 0;        // scene units; 0: unlimited
    float bias = 0;           // scene units subtracted from every distance
    bool jitter = true;       // start offset of up to one max step, per pixel
    bool centered = true;     // penumbrae straddling the hard edge (see above); false: RTSDF's
    int maxSteps = 256;
    float epsilon = 1e-4f;  // a distance below this is a hit: visibility 0
};

struct SoftShadowResult {
    float visibility = 1;  // [0, 1]
    int evaluations = 0;
};

// One march as a state machine (as the sphere tracer's, docs/design.md): start(), then step() with
// each distance at point() until it returns false; result() then holds the visibility. Scalar,
// packet and per-pixel (render/direct_pixel.h) drivers share it.
class SoftShadowMarch {
  public:
    // Marches origin + t dir (dir unit) for t in [tMin, tMax). `tanRadius`: the tangent of the
    // light's angular radius at the origin (light_sample.h; 0: a hard shadow, +inf: inside the
    // light). `jitter01` in [0, 1): the start offset in units of the max step.
    SDFT_HOST_DEVICE void start(Vec3 origin, Vec3 dir, float tMin, float tMax, float tanRadius,
                                const SoftShadowOptions& o, float jitter01) {
        m_origin = origin;
        m_dir = dir;
        m_tMax = tMax;
        m_k = tanRadius > 0 ? 1.0f / tanRadius : 0.0f;
        m_centered = o.centered && m_k > 0;
        m_t = tMin + (o.jitter && o.maxStep > 0 ? jitter01 * o.maxStep : 0.0f);
        m_prev = INFINITY;
        m_s = 1.0f;  // the closest approach in light radii (RTSDF: the visibility itself)
        m_evaluations = 0;
        m_inside = !(tanRadius < INFINITY);  // inside the light: nothing can cover all of it
        m_active = !m_inside && m_t < m_tMax && o.maxSteps > 0;
    }
    SDFT_HOST_DEVICE bool active() const { return m_active; }
    SDFT_HOST_DEVICE Vec3 point() const { return m_origin + m_dir * m_t; }
    // Takes the distance bound f/L at point(); false once the march is over.
    SDFT_HOST_DEVICE bool step(float h, const SoftShadowOptions& o) {
        ++m_evaluations;
        if (m_k > 0) {
            if (!m_centered && h < o.epsilon) {
                m_s = 0;
                return m_active = false;
            }
            float clearance;
            if (o.triangulate && m_prev < INFINITY && h > 0 && m_prev > 0) {
                // E: where the spheres of the two samples come closest to the ray.
                const float y = h * h / (2.0f * m_prev);
                const float d = std::sqrt(std::fmax(0.0f, h * h - y * y));
                clearance = d / std::fmax(m_t - y, 1e-12f);
            } else {
                clearance = h / std::fmax(m_t, 1e-12f);
            }
            m_s = minf(m_s, m_k * clearance);
            if (m_centered && m_s <= -1.0f) return m_active = false;
        } else if (h < o.epsilon) {  // a point light: a hard shadow
            m_s = m_centered ? -1.0f : 0.0f;
            return m_active = false;
        }
        m_prev = h;
        // Inside an occluder (centred) the distance is negative: step by its size, at least a
        // small fraction of t so the march gets through.
        float step = std::fabs(h);
        if (m_centered) step = std::fmax(step, std::fmax(o.epsilon, 2e-3f * m_t));
        m_t += o.maxStep > 0 ? minf(step, o.maxStep) : step;
        return m_active = m_t < m_tMax && m_evaluations < o.maxSteps;
    }
    SDFT_HOST_DEVICE SoftShadowResult result() const {
        SoftShadowResult r;
        r.evaluations = m_evaluations;
        if (m_inside) return r;
        r.visibility = m_centered ? diskShare(m_s) : clampf(m_s, 0.0f, 1.0f);
        return r;
    }

    // The visible share of a disk whose edge-to-centre offset is s radii (s = -1: hidden,
    // 1: clear).
    SDFT_HOST_DEVICE static float diskShare(float s) {
        s = clampf(s, -1.0f, 1.0f);
        return 0.5f + (s * std::sqrt(1.0f - s * s) + std::asin(s)) / kPi;
    }

  private:
    Vec3 m_origin, m_dir;
    float m_t = 0, m_tMax = 0, m_k = 0, m_prev = INFINITY, m_s = 1;
    int m_evaluations = 0;
    bool m_centered = false, m_active = false, m_inside = false;
};

// One march through a tape's field by its scalar evaluator (a device thread's, and the CPU's
// softShadow below).
SDFT_HOST_DEVICE inline SoftShadowResult softShadowTape(const TapeView& field, Vec3 origin,
                                                        Vec3 dir, float tMin, float tMax,
                                                        float tanRadius, const SoftShadowOptions& o,
                                                        float jitter01) {
    SoftShadowMarch m;
    m.start(origin, dir, tMin, tMax, tanRadius, o, jitter01);
    const float invL = 1.0f / field.lipschitz;
    while (m.active()) m.step(evalTape(field, m.point()) * invL - o.bias, o);
    return m.result();
}

SoftShadowResult softShadow(const Tape& tape, Vec3 origin, Vec3 dir, float tMin, float tMax,
                            float tanRadius, const SoftShadowOptions& options, float jitter01);

// Marches every ray together, the live ones' points evaluated in one batch per step.
struct SoftShadowRay {
    Vec3 origin, dir;
    float tMin = 0, tMax = 0, tanRadius = 0, jitter01 = 0;
};
struct SoftShadowScratch {
    std::vector<SoftShadowMarch> marches;
    std::vector<int> live;
    std::vector<float> x, y, z, f;
    BatchScratch batch;
};
void softShadowPacket(const Tape& tape, const std::vector<SoftShadowRay>& rays,
                      const SoftShadowOptions& options, std::vector<SoftShadowResult>& out,
                      SoftShadowScratch& scratch);

}  // namespace sdft
