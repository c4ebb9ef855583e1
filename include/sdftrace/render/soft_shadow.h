// SDF soft shadows: one march from a surface point towards the light's centre, estimating the
// penumbra from how closely the ray passes the scene (RTSDF §2.4-2.5, after Quilez's k·h/t).
//  - k·h/t: h/t is the tangent of the angle by which the ray clears the closest surface at t; the
//    light is taken as fully visible once that exceeds its angular radius (k = 1 / tan radius).
//    As RTSDF fig. 16 notes, this widens penumbrae outwards: the umbra is the hard shadow.
//  - Aaltonen's triangulation (RTSDF fig. 8): from two consecutive samples (distances h_prev,
//    h at t), the closest approach between them is estimated at E, y = h² / (2 h_prev) back along
//    the ray, with clearance d = sqrt(h² - y²): less banding than h/t. Ours takes the step s
//    between the samples as it was (y = (h² - h_prev² + s²) / 2s, the same for s = h_prev) and
//    uses E only where it lies between them: a ray receding from the scene has h = 2 h_prev, the
//    spheres touch at the previous sample's back and d = 0, which darkened every march that ran
//    on far past a small scene.
//  - A maximum step (RTSDF §2.5.2) so that neighbouring pixels take similar samples, and a
//    per-pixel jitter of the start within one step against the step pattern (removed by
//    accumulation).
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
#include "sdftrace/math/ray.h"

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
    // light). `jitter01` in [0, 1): the start offset in units of the max step. `tLeave`: where
    // the ray leaves the scene (softShadowEnd); the march ends with its first sample past it,
    // whose pairing with the last one inside still catches an edge on the way out.
    SDFT_HOST_DEVICE void start(Vec3 origin, Vec3 dir, float tMin, float tMax, float tanRadius,
                                const SoftShadowOptions& o, float jitter01,
                                float tLeave = INFINITY) {
        m_origin = origin;
        m_dir = dir;
        m_tMax = tMax;
        m_tLeave = tLeave;
        m_k = tanRadius > 0 ? 1.0f / tanRadius : 0.0f;
        m_centered = o.centered && m_k > 0;
        m_t = tMin + (o.jitter && o.maxStep > 0 ? jitter01 * o.maxStep : 0.0f);
        m_prev = INFINITY;
        m_step = 0;
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
            float clearance = h / std::fmax(m_t, 1e-12f);
            if (o.triangulate && m_prev < INFINITY && h > 0 && m_prev > 0) {
                // E: where the spheres of the two samples, m_step apart, meet closest to the
                // ray, y back from this sample (Aaltonen's y = h² / (2 h_prev) for a step of
                // h_prev). Only an E between the two samples says more than their own h/t; past
                // the last sample (a ray leaving the scene: h = 2 h_prev, where Aaltonen's d is
                // 0) or with one sphere inside the other, this sample's h/t stands.
                const float y = (h * h - m_prev * m_prev + m_step * m_step) / (2.0f * m_step);
                const float d2 = h * h - y * y;
                if (y > 0 && y < m_step && d2 > 0)
                    clearance = std::sqrt(d2) / std::fmax(m_t - y, 1e-12f);
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
        if (m_t >= m_tLeave) return m_active = false;
        m_step = o.maxStep > 0 ? minf(step, o.maxStep) : step;
        m_t += m_step;
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
    float m_t = 0, m_tMax = 0, m_tLeave = INFINITY, m_k = 0, m_prev = INFINITY, m_s = 1, m_step = 0;
    int m_evaluations = 0;
    bool m_centered = false, m_active = false, m_inside = false;
};

// Where a march towards a light leaves the field's bounds grown by the bias (which thickens
// every surface), beyond which nothing occludes: at most tMax, tMin where it misses them
// (SoftShadowMarch's tLeave). A directional light's march would otherwise run on to
// max_distance: up to `maxSteps` evaluations under a max step, and a far field of doubling steps
// past a small scene.
SDFT_HOST_DEVICE inline float softShadowEnd(const Bounds3& bounds, Vec3 origin, Vec3 dir,
                                            float tMin, float tMax, float bias) {
    const Vec3 grow(std::fmax(bias, 0.0f));
    float t0, t1;
    return intersectBounds({bounds.lo - grow, bounds.hi + grow}, {origin, dir}, tMin, tMax, t0, t1)
               ? t1
               : tMin;
}

// One march through a tape's field by its scalar evaluator (a device thread's, and the CPU's
// softShadow below), ending where the ray leaves the field's bounds.
SDFT_HOST_DEVICE inline SoftShadowResult softShadowTape(const TapeView& field, Vec3 origin,
                                                        Vec3 dir, float tMin, float tMax,
                                                        float tanRadius, const SoftShadowOptions& o,
                                                        float jitter01) {
    SoftShadowMarch m;
    m.start(origin, dir, tMin, tMax, tanRadius, o, jitter01,
            softShadowEnd(field.bounds, origin, dir, tMin, tMax, o.bias));
    const float invL = 1.0f / field.lipschitz;
    while (m.active()) m.step(evalTape(field, m.point()) * invL - o.bias, o);
    return m.result();
}

SoftShadowResult softShadow(const Tape& tape, Vec3 origin, Vec3 dir, float tMin, float tMax,
                            float tanRadius, const SoftShadowOptions& options, float jitter01);

// Marches every ray together, the live ones' points evaluated in one batch per step; each ends
// where it leaves the tape's bounds.
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
