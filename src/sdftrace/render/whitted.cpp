#include "sdftrace/render/whitted.h"

#include <algorithm>
#include <cmath>

#include "sdftrace/render/light_sample.h"
#include "sdftrace/render/material_at.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/trace/field_tracer.h"

namespace sdft {

WhittedTracer::WhittedTracer(const RenderPlan& plan, Visibility visibility)
    : m_plan(plan), m_tape(plan.tape), m_visibility(std::move(visibility)) {
    m_trace = plan.settings.trace.secondary();  // a secondary ray has no pixel footprint
}

Material WhittedTracer::materialAt(Vec3 p, Vec3 n) const { return sdft::materialAt(m_plan, p, n); }

// Keinert et al. 2014, §3.3.
float WhittedTracer::offset(float f) const {
    const RenderSettings& s = m_plan.settings;
    return s.dynamicEpsilon ? 2.0f * std::max(s.shadowOffsetMin, std::fabs(f) / m_tape.lipschitz())
                            : s.globalEpsilon;
}

Vec3 WhittedTracer::normalAt(Vec3 p) const {
    const Vec3 n =
        estimateNormal(m_tape, p, m_plan.settings.normalSpacingMin, m_plan.settings.normals);
    return length(n) > 0 ? n : Vec3(0, 1, 0);
}

Vec3 WhittedTracer::shadeDirect(Vec3 p, Vec3 n, Vec3 d, const Material& m,
                                WhittedStats& stats) const {
    Vec3 c = m_plan.lighting.ambient * m.color;
    const auto& lights = m_plan.lighting.lights;
    for (size_t li = 0; li < lights.size(); ++li) {
        const LightDirection to = towardLight(lights[li], p);
        if (dot(n, to.dir) <= 0) continue;
        float vis = 1;
        if (m_plan.settings.shadows && lights[li].castShadows)
            vis = m_visibility(p, n, lights[li], static_cast<int>(li), stats.shadowEvaluations);
        if (vis <= 0) continue;
        c +=
            blinnPhong(m.color, m.diffuse, m.specular, std::fmax(m.shininess, 1.0f), n, to.dir, d) *
            lights[li].color * (to.scale * vis);
    }
    return c;
}

Vec3 WhittedTracer::shadeSpecular(Vec3 p, Vec3 n, float f, Vec3 d, const Material& m,
                                  WhittedStats& stats) const {
    return shade(p, n, f, d, m, m_plan.settings.maxReflections, m_plan.settings.maxRefractions,
                 stats);
}

Vec3 WhittedTracer::shade(Vec3 p, Vec3 n, float f, Vec3 d, const Material& m, int reflections,
                          int refractions, WhittedStats& stats) const {
    if (dot(n, d) > 0) n = -n;  // seen from behind (an open or thin surface)
    const float eps = offset(f);
    switch (m.kind) {
        case Material::Kind::Plastic:
            return shadeDirect(p, n, d, m, stats);
        case Material::Kind::Mirror:
            if (reflections <= 0) return Vec3(0.0f);
            return m.color * traceOutside(p + n * eps, reflect(d, n), reflections - 1, refractions,
                                          eps, stats);
        case Material::Kind::Dielectric: {
            const float cosI = -dot(d, n);
            const float r = fresnelDielectric(cosI, 1.0f, m.ior);
            Vec3 c(0.0f);
            if (reflections > 0)
                c += traceOutside(p + n * eps, reflect(d, n), reflections - 1, refractions, eps,
                                  stats) *
                     r;
            Vec3 t;
            if (refractions > 0 && r < 1 && refract(d, n, 1.0f / m.ior, t))
                c += traceInside(p - n * eps, t, m, reflections, refractions - 1, eps, stats) *
                     (1 - r);
            return c;
        }
    }
    return Vec3(0.0f);
}

Vec3 WhittedTracer::traceOutside(Vec3 origin, Vec3 d, int reflections, int refractions, float eps,
                                 WhittedStats& stats) const {
    const TraceResult r =
        traceRay(m_tape, {{origin, d}, 0.0f, m_plan.settings.maxDistance}, m_trace);
    ++stats.rays;
    stats.evaluations += r.evaluations;
    if (!r.hit) return m_plan.lighting.background;
    if (r.t <= 2 * eps) ++stats.selfIntersections;
    const Vec3 p = origin + d * r.t;
    const Vec3 n = normalAt(p);
    return shade(p, n, r.value, d, materialAt(p, n), reflections, refractions, stats);
}

bool WhittedTracer::exitDistance(Vec3 origin, Vec3 d, float& dist, float& value,
                                 WhittedStats& stats) const {
    // Keinert §3.5: inside a convex object, from its bound's far side back along -d.
    for (const ConvexObject& c : m_plan.convexObjects) {
        if (!c.bounds.contains(origin)) continue;
        const float f = c.tape.eval(origin);
        ++stats.evaluations;
        if (f >= 0) continue;
        float tFar = INFINITY;
        for (int a = 0; a < 3; ++a) {
            if (d[a] > 0) tFar = std::min(tFar, (c.bounds.hi[a] - origin[a]) / d[a]);
            if (d[a] < 0) tFar = std::min(tFar, (c.bounds.lo[a] - origin[a]) / d[a]);
        }
        const float margin = 1e-3f * length(c.bounds.extent()) + 1e-6f;
        const float start = tFar + margin;
        const Vec3 q = origin + d * start;
        const TraceResult back = traceRay(c.tape, {{q, -d}, 0.0f, start}, m_trace);
        stats.evaluations += back.evaluations;
        if (!back.hit) break;  // rounding: march through the interior instead
        // The object's exit is the scene's only where no other object covers it (objects that
        // overlap, e.g. one sunk into the floor, march through the interior instead).
        const float scene = m_tape.eval(q - d * back.t) / m_tape.lipschitz();
        ++stats.evaluations;
        if (scene < back.value / c.tape.lipschitz() - 2 * m_trace.tau) break;
        dist = std::max(0.0f, start - back.t);
        value = -back.value;
        return true;
    }
    SphereTraceState s;
    const float invL = 1.0f / m_tape.lipschitz();
    sphereTraceBegin(s, {origin, d}, 0.0f, m_plan.settings.maxDistance, Bounds3::everything(),
                     m_trace);
    while (!s.done()) sphereTraceAdvance(s, -m_tape.eval(s.queryPoint()), invL, m_trace);
    stats.evaluations += s.result.evaluations;
    if (!s.result.hit) return false;
    dist = s.result.t;
    value = s.result.value;
    return true;
}

// Inside a dielectric: find the exit (through the interior, or Keinert §3.5's bound), attenuate,
// then split at the exit.
Vec3 WhittedTracer::traceInside(Vec3 origin, Vec3 d, const Material& m, int reflections,
                                int refractions, float eps, WhittedStats& stats) const {
    float dist = 0, value = 0;
    ++stats.rays;
    if (!exitDistance(origin, d, dist, value, stats)) return Vec3(0.0f);
    if (dist <= 2 * eps) ++stats.selfIntersections;
    const Vec3 att(std::exp(-m.absorption.x * dist), std::exp(-m.absorption.y * dist),
                   std::exp(-m.absorption.z * dist));
    const Vec3 q = origin + d * dist;
    const Vec3 nOut = normalAt(q);  // the outward normal: d leaves along it
    const float e = offset(value);
    const float cosI = dot(d, nOut);
    const float r = fresnelDielectric(cosI, m.ior, 1.0f);
    Vec3 c(0.0f);
    Vec3 t;
    if (r < 1 && refract(d, -nOut, m.ior, t))
        c += traceOutside(q + nOut * e, t, reflections, refractions, e, stats) * (1 - r);
    if (refractions > 0)
        c += traceInside(q - nOut * e, reflect(d, -nOut), m, reflections, refractions - 1, e,
                         stats) *
             r;
    return c * att;
}

}  // namespace sdft
