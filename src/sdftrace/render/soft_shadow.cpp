#include "sdftrace/render/soft_shadow.h"

#include <algorithm>
#include <cmath>

namespace sdft {

namespace {

// The visible share of a disk whose edge-to-centre offset is s radii (s = -1: hidden, 1: clear).
float diskShare(float s) {
    s = std::clamp(s, -1.0f, 1.0f);
    return 0.5f + (s * std::sqrt(1.0f - s * s) + std::asin(s)) / kPi;
}

}  // namespace

// RTSDF §2.4-2.5 (see the header).
void SoftShadowMarch::start(Vec3 origin, Vec3 dir, float tMin, float tMax, float tanRadius,
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

bool SoftShadowMarch::step(float h, const SoftShadowOptions& o) {
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
        m_s = std::min(m_s, m_k * clearance);
        if (m_centered && m_s <= -1.0f) return m_active = false;
    } else if (h < o.epsilon) {  // a point light: a hard shadow
        m_s = m_centered ? -1.0f : 0.0f;
        return m_active = false;
    }
    m_prev = h;
    // Inside an occluder (centred) the distance is negative: step by its size, at least a small
    // fraction of t so the march gets through.
    float step = std::fabs(h);
    if (m_centered) step = std::fmax(step, std::fmax(o.epsilon, 2e-3f * m_t));
    m_t += o.maxStep > 0 ? std::min(step, o.maxStep) : step;
    return m_active = m_t < m_tMax && m_evaluations < o.maxSteps;
}

SoftShadowResult SoftShadowMarch::result() const {
    SoftShadowResult r;
    r.evaluations = m_evaluations;
    if (m_inside) return r;
    r.visibility = m_centered ? diskShare(m_s) : std::clamp(m_s, 0.0f, 1.0f);
    return r;
}

SoftShadowResult softShadow(const Tape& tape, Vec3 origin, Vec3 dir, float tMin, float tMax,
                            float tanRadius, const SoftShadowOptions& o, float jitter01) {
    SoftShadowMarch m;
    m.start(origin, dir, tMin, tMax, tanRadius, o, jitter01);
    const float invL = 1.0f / tape.lipschitz();
    while (m.active()) m.step(tape.eval(m.point()) * invL - o.bias, o);
    return m.result();
}

void softShadowPacket(const Tape& tape, const std::vector<SoftShadowRay>& rays,
                      const SoftShadowOptions& o, std::vector<SoftShadowResult>& out,
                      SoftShadowScratch& s) {
    const int n = static_cast<int>(rays.size());
    s.marches.resize(n);
    s.live.clear();
    for (int i = 0; i < n; ++i) {
        const SoftShadowRay& r = rays[i];
        s.marches[i].start(r.origin, r.dir, r.tMin, r.tMax, r.tanRadius, o, r.jitter01);
        if (s.marches[i].active()) s.live.push_back(i);
    }
    const float invL = 1.0f / tape.lipschitz();
    while (!s.live.empty()) {
        const int m = static_cast<int>(s.live.size());
        s.x.resize(m);
        s.y.resize(m);
        s.z.resize(m);
        s.f.resize(m);
        for (int j = 0; j < m; ++j) {
            const Vec3 p = s.marches[s.live[j]].point();
            s.x[j] = p.x;
            s.y[j] = p.y;
            s.z[j] = p.z;
        }
        tape.evalBatch(s.x.data(), s.y.data(), s.z.data(), s.f.data(), m, s.batch);
        int kept = 0;
        for (int j = 0; j < m; ++j) {
            if (s.marches[s.live[j]].step(s.f[j] * invL - o.bias, o)) s.live[kept++] = s.live[j];
        }
        s.live.resize(kept);
    }
    out.resize(n);
    for (int i = 0; i < n; ++i) out[i] = s.marches[i].result();
}

}  // namespace sdft
