#include "sdftrace/render/path_tracer.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "sdftrace/exec/progress.h"
#include "sdftrace/exec/thread_arena.h"
#include "sdftrace/math/camera.h"
#include "sdftrace/math/sampling.h"
#include "sdftrace/render/light_sample.h"
#include "sdftrace/render/material_at.h"
#include "sdftrace/render/whitted.h"
#include "sdftrace/trace/field_tracer.h"
#include "sdftrace/trace/sphere_tracer.h"

namespace sdft {

namespace {

float maxComponent3(Vec3 v) { return std::max(v.x, std::max(v.y, v.z)); }

// GGX (Trowbridge-Reitz) normal distribution and Smith's shadowing for alpha.
float ggxD(float nh, float a) {
    const float a2 = a * a, k = nh * nh * (a2 - 1) + 1;
    return a2 / (kPi * k * k);
}
float smithG1(float nv, float a) {
    const float a2 = a * a;
    return 2 * nv / (nv + std::sqrt(a2 + (1 - a2) * nv * nv));
}

struct Plastic {
    Vec3 albedo;
    float specular, alpha, pDiffuse;
};

Plastic plastic(const Material& m) {
    Plastic p;
    p.albedo = min(m.color * m.diffuse, Vec3(0.999f));
    p.specular = std::min(m.specular, 1.0f);
    p.alpha = m.roughness >= 0 ? std::max(m.roughness, 1e-3f)
                               : std::sqrt(2.0f / (std::max(m.shininess, 1.0f) + 2.0f));
    const float wd = maxComponent3(p.albedo), ws = p.specular * 0.04f;
    p.pDiffuse = wd + ws > 0 ? wd / (wd + ws) : 1.0f;
    return p;
}

// f(wo, wi) cos(wi) of plastic, and the mixture pdf of sampling wi.
Vec3 evalPlastic(const Plastic& m, Vec3 n, Vec3 wo, Vec3 wi, float& pdf) {
    const float ni = dot(n, wi), no = dot(n, wo);
    pdf = 0;
    if (ni <= 0 || no <= 0) return Vec3(0.0f);
    // The diffuse base sees what the coat's Fresnel lets through, on the way in and out
    // (Ashikhmin & Shirley 2000 in spirit), so that the sum reflects no more than it receives.
    const auto schlick = [](float c) { return 0.04f + 0.96f * std::pow(1 - c, 5.0f); };
    Vec3 f = m.albedo * ((1 - m.specular * schlick(ni)) * (1 - m.specular * schlick(no)) / kPi);
    const Vec3 h = normalize(wo + wi);
    const float nh = std::max(dot(n, h), 0.0f), oh = std::max(dot(wo, h), 1e-6f);
    const float D = ggxD(nh, m.alpha);
    if (m.specular > 0) {
        const float F = schlick(oh);
        const float G = smithG1(no, m.alpha) * smithG1(ni, m.alpha);
        f += Vec3(m.specular * D * G * F / (4 * no * ni));
    }
    pdf = m.pDiffuse * ni / kPi + (1 - m.pDiffuse) * D * nh / (4 * oh);
    return f * ni;
}

Vec3 sampleGgx(Vec3 n, Vec3 wo, float alpha, float u1, float u2) {
    const float phi = 2 * kPi * u1;
    const float cosT = std::sqrt((1 - u2) / (1 + (alpha * alpha - 1) * u2));
    const float sinT = std::sqrt(std::max(0.0f, 1 - cosT * cosT));
    Vec3 t, b;
    orthonormalBasis(n, t, b);
    const Vec3 h = t * (sinT * std::cos(phi)) + b * (sinT * std::sin(phi)) + n * cosT;
    return h * (2 * dot(wo, h)) - wo;
}

class PathTracer {
  public:
    PathTracer(const RenderPlan& plan, const FrameView& view)
        : m_plan(plan), m_view(view), m_tape(plan.tape), m_camera(view.camera) {
        m_primary = plan.settings.trace;
        m_primary.pixelRadius = m_camera.pixelRadius();
        m_secondary = plan.settings.trace.secondary();
        m_occlusion = plan.settings.trace.occlusion();
    }

    Vec3 radiance(int x, int y, int sample, RenderStats& st, float* depth, Vec3* normal,
                  int* steps) const;

  private:
    bool trace(const Ray& ray, bool inside, bool primary, float& t, float& value,
               RenderStats& st) const;
    // Sphere traces ray on f (or -f inside) up to tMax; adds its evaluations to `evaluations`.
    bool march(const Ray& ray, float tMax, bool inside, const TraceOptions& o, float& t,
               float& value, uint64_t& evaluations) const;
    Vec3 nextEvent(Vec3 p, Vec3 n, float eps, Vec3 wo, const Plastic& m, Rng& rng,
                   RenderStats& st) const;
    float epsilon(float f) const {
        return 2.0f * std::max(m_plan.settings.shadowOffsetMin, std::fabs(f) / m_tape.lipschitz());
    }

    const RenderPlan& m_plan;
    const FrameView& m_view;
    const Tape& m_tape;
    Camera m_camera;
    TraceOptions m_primary, m_secondary, m_occlusion;
};

bool PathTracer::march(const Ray& ray, float tMax, bool inside, const TraceOptions& o, float& t,
                       float& value, uint64_t& evaluations) const {
    SphereTraceState s;
    const float invL = 1.0f / m_tape.lipschitz();
    sphereTraceBegin(s, ray, 0.0f, tMax, inside ? Bounds3::everything() : m_tape.bounds(), o);
    const float sign = inside ? -1.0f : 1.0f;
    while (!s.done()) sphereTraceAdvance(s, sign * m_tape.eval(s.queryPoint()), invL, o);
    evaluations += s.result.evaluations;
    t = s.result.t;
    value = s.result.value;
    return s.result.hit;
}

bool PathTracer::trace(const Ray& ray, bool inside, bool primary, float& t, float& value,
                       RenderStats& st) const {
    if (!primary) ++st.secondaryRays;
    return march(ray, m_plan.settings.maxDistance, inside, primary ? m_primary : m_secondary, t,
                 value, primary ? st.primaryEvaluations : st.secondaryEvaluations);
}

// One sampled point of each light, seen from p through a shadow ray that starts at p + n eps.
Vec3 PathTracer::nextEvent(Vec3 p, Vec3 n, float eps, Vec3 wo, const Plastic& m, Rng& rng,
                           RenderStats& st) const {
    Vec3 sum(0.0f);
    const auto& lights = m_plan.lighting.lights;
    for (const Light& light : lights) {
        const LightDirection to = towardLight(light, p);
        const LightSample ls = sampleLight(light, p, rng.uniform(), rng.uniform());
        float pdf;
        const Vec3 fcos = evalPlastic(m, n, wo, ls.dir, pdf);
        if (maxComponent3(fcos) <= 0) continue;
        if (m_plan.settings.shadows && light.castShadows && ls.dist > 0) {
            ++st.shadowRays;
            float t, value;
            if (march({p + n * eps, ls.dir}, std::min(ls.dist, m_plan.settings.maxDistance), false,
                      m_occlusion, t, value, st.shadowEvaluations))
                continue;
        }
        // The direct integrator's light model: pi * scale makes a white Lambertian surface's
        // radiance scale * cos.
        sum += fcos * light.color * (kPi * to.scale);
    }
    return sum;
}

Vec3 PathTracer::radiance(int x, int y, int sample, RenderStats& st, float* depthOut,
                          Vec3* normalOut, int* stepsOut) const {
    const RenderSettings& set = m_plan.settings;
    Rng rng(static_cast<uint32_t>(y * m_view.camera.width + x),
            m_view.frame * static_cast<uint32_t>(set.samplesPerPixel) + sample, 0x9A7Bu);
    Ray ray = m_camera.rayThrough(x + rng.uniform(), y + rng.uniform());
    Vec3 L(0.0f), beta(1.0f);
    bool inside = false;
    Material medium;  // the dielectric a ray inside is in
    for (int depth = 0; depth < set.maxDepth || depth == 0; ++depth) {
        float t, value;
        const uint64_t before = st.primaryEvaluations;
        const bool hit = trace(ray, inside, depth == 0, t, value, st);
        if (depth == 0) {
            ++st.primaryRays;
            if (stepsOut) *stepsOut = static_cast<int>(st.primaryEvaluations - before);
        }
        if (!hit) {
            L += beta * (depth == 0 ? m_plan.lighting.background : m_plan.lighting.environment);
            break;
        }
        if (depth == 0) ++st.hits;
        const Vec3 p = ray.at(t);
        if (inside) {
            beta =
                beta * Vec3(std::exp(-medium.absorption.x * t), std::exp(-medium.absorption.y * t),
                            std::exp(-medium.absorption.z * t));
        }
        Vec3 n = estimateNormal(m_tape, p, 1e-4f, set.normals);
        st.normalEvaluations += 4;
        if (!(length(n) > 0)) n = -ray.direction;
        if (depth == 0) {
            if (depthOut) *depthOut = t;
            if (normalOut) *normalOut = n;
        }
        const Material m = inside ? medium : materialAt(m_plan, p, n);
        const Vec3 wo = -ray.direction;
        const float eps = epsilon(value);
        if (m.kind == Material::Kind::Dielectric) {
            // n points out of the solid; entering from outside, leaving from inside.
            const bool entering = !inside;
            const Vec3 nf = entering ? n : -n;  // facing the incoming ray
            const float n1 = entering ? 1.0f : m.ior, n2 = entering ? m.ior : 1.0f;
            const float cosI = std::clamp(dot(wo, nf), 0.0f, 1.0f);
            const float F = fresnelDielectric(cosI, n1, n2);
            Vec3 dir;
            if (rng.uniform() < F || !refract(ray.direction, nf, n1 / n2, dir)) {
                ray = {p + nf * eps, reflect(ray.direction, nf)};
            } else {
                ray = {p - nf * eps, dir};
                inside = entering;
                medium = m;
            }
        } else if (m.kind == Material::Kind::Mirror) {
            const Vec3 nf = dot(n, wo) > 0 ? n : -n;
            beta = beta * m.color;
            ray = {p + nf * eps, reflect(ray.direction, nf)};
        } else {
            const Vec3 nf = dot(n, wo) > 0 ? n : -n;
            const Plastic pm = plastic(m);
            L += beta * nextEvent(p, nf, eps, wo, pm, rng, st);
            if (depth + 1 >= set.maxDepth) break;
            // Sample the mixture: cosine lobe or GGX reflection.
            const float u1 = rng.uniform(), u2 = rng.uniform();
            const Vec3 wi = rng.uniform() < pm.pDiffuse ? sampleCosine(nf, u1, u2)
                                                        : sampleGgx(nf, wo, pm.alpha, u1, u2);
            float pdf;
            const Vec3 fcos = evalPlastic(pm, nf, wo, wi, pdf);
            if (!(pdf > 0) || maxComponent3(fcos) <= 0) break;
            beta = beta * fcos / pdf;
            ray = {p + nf * eps, wi};
        }
        // Russian roulette after three bounces.
        if (depth >= 3) {
            const float q = std::max(0.05f, 1 - maxComponent3(beta));
            if (rng.uniform() < q) break;
            beta = beta / (1 - q);
        }
    }
    return isFinite(L) ? L : Vec3(0.0f);
}

}  // namespace

struct PathFrame::Impl {
    Impl(const RenderPlan& plan, const FrameView& view, Film& f) : tracer(plan, view), film(f) {}
    PathTracer tracer;
    Film& film;
    int spp = 1;
};

PathFrame::PathFrame(const RenderPlan& plan, const FrameView& view, Film& film)
    : m_impl(std::make_unique<Impl>(plan, view, film)) {
    m_impl->spp = std::max(1, plan.settings.samplesPerPixel);
}

PathFrame::~PathFrame() = default;

void PathFrame::render(const PixelRect& r, RenderStats& st) const {
    Film& film = m_impl->film;
    const int spp = m_impl->spp;
    const bool normals = film.has(Aov::Normal), depths = film.has(Aov::Depth),
               keepSteps = film.has(Aov::Steps);
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) {
            const size_t p = static_cast<size_t>(y) * film.width + x;
            Vec3 sum(0.0f), normal(0.0f);
            float depth = INFINITY;
            int steps = 0;
            for (int k = 0; k < spp; ++k)
                sum +=
                    m_impl->tracer.radiance(x, y, k, st, k == 0 ? &depth : nullptr,
                                            k == 0 ? &normal : nullptr, k == 0 ? &steps : nullptr);
            const Vec3 c = sum / static_cast<float>(spp);
            for (int a = 0; a < 3; ++a) {
                film.color[3 * p + a] = c[a];
                if (normals) film.normal[3 * p + a] = normal[a];
            }
            if (depths) film.depth[p] = depth;
            if (keepSteps) film.steps[p] = static_cast<float>(steps);
        }
}

RenderStats renderPaths(const RenderPlan& plan, const FrameView& view, Film& film, bool progress) {
    FrameRenderer frame(plan, view, film);
    Progress bar("path tracing", static_cast<uint64_t>(frame.tileCount()), progress);
    frame.renderTiles(0, frame.tileCount(), &bar);
    return frame.stats();
}

}  // namespace sdft
