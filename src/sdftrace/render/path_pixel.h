// One path of the progressive path tracer (path_tracer.h; Kajiya 1986, Keinert et al. 2014 fig. 1
// right) as a header function over plain data: the CPU's PathFrame and the GPU's kernel
// (gpu/gpu_render.cu) both run pathRadiance, the CPU with the plan's materialAt, the GPU with the
// per-pixel material table (both texture colours with render/texture.h). Next-event estimation at
// every non-specular vertex, plastic as Lambert + GGX (Schlick F0 = 0.04), mirrors, dielectrics
// with Fresnel and Beer-Lambert absorption, a constant environment, Russian roulette after three
// bounces.
#pragma once

#include <cmath>
#include <cstdint>

#include "sdftrace/math/sampling.h"
#include "sdftrace/render/direct_pixel.h"
#include "sdftrace/render/light_sample.h"
#include "sdftrace/render/normal_stencil.h"
#include "sdftrace/render/optics.h"
#include "sdftrace/trace/sphere_tracer.h"

namespace sdft {

struct RenderPlan;
struct FrameView;

// Plain data: the direct view's field, camera, primary options, lights and material table, and
// what paths add.
struct PathPixelView {
    DirectPixelView direct;
    TraceOptions secondary, occlusion;
    float offsetMin = 1e-3f;  // RenderSettings::shadowOffsetMin (not a DDA grid's half voxel)
    Vec3 environment{0, 0, 0};
    int maxDepth = 5, samplesPerPixel = 16;
    int seedWidth = 0;  // the camera's width: pixel (x, y) seeds with y * seedWidth + x
};

// What one path cost (RenderStats' fields of the same names).
struct PathCounters {
    uint64_t primaryRays = 0, primaryEvaluations = 0, hits = 0, normalEvaluations = 0;
    uint64_t shadowRays = 0, shadowEvaluations = 0, secondaryRays = 0, secondaryEvaluations = 0;
};

namespace path_pixel {

SDFT_HOST_DEVICE inline float maxComponent3(Vec3 v) { return maxf(v.x, maxf(v.y, v.z)); }

// GGX (Trowbridge-Reitz) normal distribution and Smith's shadowing for alpha.
SDFT_HOST_DEVICE inline float ggxD(float nh, float a) {
    const float a2 = a * a, k = nh * nh * (a2 - 1) + 1;
    return a2 / (kPi * k * k);
}
SDFT_HOST_DEVICE inline float smithG1(float nv, float a) {
    const float a2 = a * a;
    return 2 * nv / (nv + std::sqrt(a2 + (1 - a2) * nv * nv));
}

struct Plastic {
    Vec3 albedo;
    float specular, alpha, pDiffuse;
};

SDFT_HOST_DEVICE inline Plastic plastic(const PixelMaterial& m) {
    Plastic p;
    p.albedo = min(m.color * m.diffuse, Vec3(0.999f));
    p.specular = minf(m.specular, 1.0f);
    p.alpha = m.roughness >= 0 ? maxf(m.roughness, 1e-3f)
                               : std::sqrt(2.0f / (maxf(m.shininess, 1.0f) + 2.0f));
    const float wd = maxComponent3(p.albedo), ws = p.specular * 0.04f;
    p.pDiffuse = wd + ws > 0 ? wd / (wd + ws) : 1.0f;
    return p;
}

SDFT_HOST_DEVICE inline float schlick(float c) { return 0.04f + 0.96f * powf(1 - c, 5.0f); }

// f(wo, wi) cos(wi) of plastic, and the mixture pdf of sampling wi.
SDFT_HOST_DEVICE inline Vec3 evalPlastic(const Plastic& m, Vec3 n, Vec3 wo, Vec3 wi, float& pdf) {
    const float ni = dot(n, wi), no = dot(n, wo);
    pdf = 0;
    if (ni <= 0 || no <= 0) return Vec3(0.0f);
    // The diffuse base sees what the coat's Fresnel lets through, on the way in and out
    // (Ashikhmin & Shirley 2000 in spirit), so that the sum reflects no more than it receives.
    Vec3 f = m.albedo * ((1 - m.specular * schlick(ni)) * (1 - m.specular * schlick(no)) / kPi);
    const Vec3 h = normalize(wo + wi);
    const float nh = maxf(dot(n, h), 0.0f), oh = maxf(dot(wo, h), 1e-6f);
    const float D = ggxD(nh, m.alpha);
    if (m.specular > 0) {
        const float F = schlick(oh);
        const float G = smithG1(no, m.alpha) * smithG1(ni, m.alpha);
        f += Vec3(m.specular * D * G * F / (4 * no * ni));
    }
    pdf = m.pDiffuse * ni / kPi + (1 - m.pDiffuse) * D * nh / (4 * oh);
    return f * ni;
}

SDFT_HOST_DEVICE inline Vec3 sampleGgx(Vec3 n, Vec3 wo, float alpha, float u1, float u2) {
    const float phi = 2 * kPi * u1;
    const float cosT = std::sqrt((1 - u2) / (1 + (alpha * alpha - 1) * u2));
    const float sinT = std::sqrt(maxf(0.0f, 1 - cosT * cosT));
    Vec3 t, b;
    orthonormalBasis(n, t, b);
    const Vec3 h = t * (sinT * cosf(phi)) + b * (sinT * sinf(phi)) + n * cosT;
    return h * (2 * dot(wo, h)) - wo;
}

// Sphere traces ray on f (or -f inside) up to tMax; adds its evaluations to `evaluations`.
SDFT_HOST_DEVICE inline bool march(const TapeView& field, const Ray& ray, float tMax, bool inside,
                                   const TraceOptions& o, float& t, float& value,
                                   uint64_t& evaluations) {
    SphereTraceState s;
    const float invL = 1.0f / field.lipschitz;
    const Bounds3 everywhere{Vec3(-kInfinity), Vec3(kInfinity)};
    sphereTraceBegin(s, ray, 0.0f, tMax, inside ? everywhere : field.bounds, o);
    const float sign = inside ? -1.0f : 1.0f;
    while (!s.done()) sphereTraceAdvance(s, sign * evalTape(field, s.queryPoint()), invL, o);
    evaluations += static_cast<uint64_t>(s.result.evaluations);
    t = s.result.t;
    value = s.result.value;
    return s.result.hit;
}

// One sampled point of each light, seen from p through a shadow ray that starts at p + n eps.
SDFT_HOST_DEVICE inline Vec3 nextEvent(const PathPixelView& v, Vec3 p, Vec3 n, float eps, Vec3 wo,
                                       const Plastic& m, Rng& rng, PathCounters& c) {
    const DirectPixelView& d = v.direct;
    Vec3 sum(0.0f);
    for (int li = 0; li < d.lightCount; ++li) {
        const Light& light = d.lights[li];
        const LightDirection to = towardLight(light, p);
        const float u1 = rng.uniform(), u2 = rng.uniform();
        const LightSample ls = sampleLight(light, p, u1, u2);
        float pdf;
        const Vec3 fcos = evalPlastic(m, n, wo, ls.dir, pdf);
        if (maxComponent3(fcos) <= 0) continue;
        if (d.shadows && light.castShadows && ls.dist > 0) {
            ++c.shadowRays;
            float t, value;
            if (march(d.primary.field, {p + n * eps, ls.dir}, minf(ls.dist, d.primary.maxDistance),
                      false, v.occlusion, t, value, c.shadowEvaluations))
                continue;
        }
        // The direct integrator's light model: pi * scale makes a white Lambertian surface's
        // radiance scale * cos.
        sum += fcos * light.color * (kPi * to.scale);
    }
    return sum;
}

}  // namespace path_pixel

// Sample `sample` of pixel (x, y): the radiance of one path. materialAt(p, n) gives the material
// at a hit (a PixelMaterial). The first sample reports depth, normal and primary steps where
// asked.
template <class MaterialAt>
SDFT_HOST_DEVICE inline Vec3 pathRadiance(const PathPixelView& v, const MaterialAt& materialAt,
                                          int x, int y, int sample, PathCounters& c,
                                          float* depthOut, Vec3* normalOut, int* stepsOut) {
    using namespace path_pixel;
    const DirectPixelView& d = v.direct;
    const TapeView& field = d.primary.field;
    Rng rng(static_cast<uint32_t>(y * v.seedWidth + x),
            d.frame * static_cast<uint32_t>(v.samplesPerPixel) + static_cast<uint32_t>(sample),
            0x9A7Bu);
    const float jx = rng.uniform(), jy = rng.uniform();
    Ray ray = d.primary.camera.rayThrough(x + jx, y + jy);
    Vec3 L(0.0f), beta(1.0f);
    bool inside = false;
    PixelMaterial medium;  // the dielectric a ray inside is in
    for (int depth = 0; depth < v.maxDepth || depth == 0; ++depth) {
        float t, value;
        bool hit;
        if (depth == 0) {
            const uint64_t before = c.primaryEvaluations;
            hit = march(field, ray, d.primary.maxDistance, inside, d.primary.options, t, value,
                        c.primaryEvaluations);
            ++c.primaryRays;
            if (stepsOut) *stepsOut = static_cast<int>(c.primaryEvaluations - before);
        } else {
            ++c.secondaryRays;
            hit = march(field, ray, d.primary.maxDistance, inside, v.secondary, t, value,
                        c.secondaryEvaluations);
        }
        if (!hit && !inside && horizonHit(d.primary.horizon, ray, t)) {
            hit = true;  // a top-level plane past the rest of the scene
            value = 0;
        }
        if (!hit) {
            L += beta * (depth == 0 ? d.background : v.environment);
            break;
        }
        if (depth == 0) ++c.hits;
        const Vec3 p = ray.at(t);
        if (inside) {
            beta = beta * Vec3(expf(-medium.absorption.x * t), expf(-medium.absorption.y * t),
                               expf(-medium.absorption.z * t));
        }
        Vec3 n = estimateTapeNormal(field, p, d.primary.normalSpacingMin, d.primary.normals);
        c.normalEvaluations += 4;
        if (!(length(n) > 0)) n = -ray.direction;
        if (depth == 0) {
            if (depthOut) *depthOut = t;
            if (normalOut) *normalOut = n;
        }
        const PixelMaterial m = inside ? medium : materialAt(p, n);
        const Vec3 wo = -ray.direction;
        const float eps = 2.0f * maxf(v.offsetMin, std::fabs(value) / field.lipschitz);
        if (m.kind == Material::Kind::Dielectric) {
            // n points out of the solid; entering from outside, leaving from inside.
            const bool entering = !inside;
            const Vec3 nf = entering ? n : -n;  // facing the incoming ray
            const float n1 = entering ? 1.0f : m.ior, n2 = entering ? m.ior : 1.0f;
            const float cosI = clampf(dot(wo, nf), 0.0f, 1.0f);
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
            L += beta * nextEvent(v, p, nf, eps, wo, pm, rng, c);
            if (depth + 1 >= v.maxDepth) break;
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
            const float q = maxf(0.05f, 1 - maxComponent3(beta));
            if (rng.uniform() < q) break;
            beta = beta / (1 - q);
        }
    }
    return isFinite(L) ? L : Vec3(0.0f);
}

// The view of `plan` for one frame, its lights and material table `tables`'s.
PathPixelView pathPixelView(const RenderPlan& plan, const FrameView& frame,
                            const DirectPixelTables& tables);

}  // namespace sdft
