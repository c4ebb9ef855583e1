// Whitted ray tracing (Whitted 1980) over distance bounds, as Keinert et al. 2014 §4 use it for
// their translucent scenes, per pixel: the one implementation, which the CPU renderer runs for its
// tiles' mirror and glass hits and a device thread for its pixel. Mirrors reflect; dielectrics
// split into Fresnel-weighted reflection and refraction (Snell, total internal reflection,
// Beer-Lambert absorption inside); rays inside an object are sphere traced on -f to the exit.
// Each kind of bounce has its own budget (Keinert: 2 reflections, 8 refractions); a ray out of
// budget is dark. Secondary rays start off the surface by Keinert §3.3's dynamic epsilon,
// 2 max(eps_min, |f(p)|), or by a global epsilon (selectable, to show the acne the global one
// gives when hits lie up to half a pixel from the surface).
//
// Keinert §3.5, convex objects in convex bounds: a refracted ray inside a convex object (a
// top-level object built from convex primitives by intersections and transforms) does not march
// through the interior; it jumps to where it leaves the object's bounding box and sphere traces
// back along -d on the object's own field, which finds the same exit point in fewer steps.
//
// The ray tree is a loop over a bounded explicit stack of pending rays, each carrying the weight
// its path multiplies in (no recursion, no std::function: a device thread runs it). Secondary
// hits on plastic see the lights by the settings' shadow method without per-pixel random numbers
// (secondaryVisibility: hard rays, soft shadows without jitter, distributed rays on a fixed Halton
// rotation), or by the CPU renderer's shadow maps.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "sdftrace/render/direct_pixel.h"
#include "sdftrace/render/normal_stencil.h"
#include "sdftrace/render/optics.h"
#include "sdftrace/trace/sphere_tracer.h"

namespace sdft {

struct RenderPlan;

// The pending rays a budget of `bounces` reflections and refractions in all (max_reflections +
// max_refractions) needs: a path alternates at most 2 (R + F) + 1 rays deep (an exit keeps the
// budgets, the next entry spends one), and each level leaves at most one ray pending.
constexpr int whittedStackFor(int bounces) { return 2 * bounces + 2; }
// A device thread's stack holds budgets of up to kWhittedMaxBounces (directPixelUnsupported
// names deeper ones); the CPU renderer's holds every budget the render options accept (64 + 64).
inline constexpr int kWhittedMaxBounces = 16;
inline constexpr int kWhittedStack = whittedStackFor(kWhittedMaxBounces);
inline constexpr int kWhittedMaxBouncesCpu = 128;
inline constexpr int kWhittedStackCpu = whittedStackFor(kWhittedMaxBouncesCpu);

// A convex top-level object (Keinert §3.5): its own tape and bounding box.
struct ConvexView {
    TapeView tape;
    Bounds3 bounds;
};

// How secondary hits see the lights: the settings' shadow method without per-pixel random
// numbers (shadow maps excepted: the renderer's own).
struct SecondaryShadows {
    bool enabled = true;  // RenderSettings::shadows
    ShadowMethod method = ShadowMethod::Hard;
    int rays = 1;             // distributed rays, on a fixed Halton rotation
    float offsetMin = 1e-3f;  // the rays start 2 eps_min off the surface
    float maxDistance = kInfinity;
    TraceOptions ray;        // hit or miss only
    SoftShadowOptions soft;  // no finer than the primary rays' tau, no jitter
};
SecondaryShadows secondaryShadows(const RenderSettings& settings);

// How much of `light` the secondary hit p (unit normal n) on `field` sees, in [0, 1]: the CPU
// renderer's visibilityAt for its Whitted rays, and the per-pixel path's; the field evaluations
// are added to `evaluations` (the summary's shadow evaluations).
SDFT_HOST_DEVICE inline float secondaryVisibility(const TapeView& field, const SecondaryShadows& s,
                                                  Vec3 p, Vec3 n, const Light& light,
                                                  uint32_t& evaluations) {
    const LightDirection to = towardLight(light, p);
    if (dot(n, to.dir) <= 0) return 0.0f;
    const Vec3 origin = p + n * (2.0f * s.offsetMin);
    const float tMax = minf(to.dist, s.maxDistance);
    auto blocked = [&](Vec3 dir, float t) {
        const TraceResult r = traceTapeRay(field, {{origin, dir}, 0.0f, t}, s.ray);
        evaluations += static_cast<uint32_t>(r.evaluations);
        return r.hit;
    };
    if (s.method == ShadowMethod::Soft) {
        const SoftShadowResult r = softShadowTape(field, origin, to.dir, 0.0f, tMax,
                                                  lightTanRadius(light, p), s.soft, 0.0f);
        evaluations += static_cast<uint32_t>(r.evaluations);
        return r.visibility;
    }
    if (s.method != ShadowMethod::Distributed || !light.hasSize())
        return blocked(to.dir, tMax) ? 0.0f : 1.0f;
    int seen = 0;
    for (int k = 0; k < s.rays; ++k) {
        float u1, u2;
        rotatedHalton(static_cast<uint32_t>(k), 0.5f, 0.5f, u1, u2);
        const LightSample ls = sampleLight(light, p, u1, u2);
        if (ls.dist <= 0) {
            ++seen;
        } else if (dot(n, ls.dir) > 0) {
            seen += !blocked(ls.dir, ls.dist);
        }
    }
    return static_cast<float>(seen) / static_cast<float>(s.rays);
}

// Plain data: the settings Whitted rays read, and the convex objects' tapes (the caller's arrays).
struct WhittedPixelView {
    const ConvexView* convex = nullptr;
    int convexCount = 0;
    int maxReflections = 2, maxRefractions = 8;
    bool dynamicEpsilon = true;
    float globalEpsilon = 1e-3f;
    float offsetMin = 1e-3f;   // eps_min of §3.3 (RenderSettings::shadowOffsetMin)
    TraceOptions secondary;    // no pixel footprint
    SecondaryShadows shadows;  // at secondary hits on plastic
};

struct WhittedCounters {
    uint32_t rays = 0, evaluations = 0;
    uint32_t selfIntersections = 0;  // rays that struck the surface they left within 2 offsets
    uint32_t shadowEvaluations = 0;  // of the secondary hits' shadow rays
};

namespace whitted_pixel {

// A ray waiting on the stack: outside the solid, or inside a dielectric of index `ior`.
struct PendingRay {
    Vec3 origin, dir, weight;
    Vec3 absorption;
    float ior, eps;
    int8_t reflections, refractions;
    bool inside;
};

// Keinert et al. 2014, §3.3.
SDFT_HOST_DEVICE inline float offset(const DirectPixelView& v, const WhittedPixelView& w, float f) {
    return w.dynamicEpsilon ? 2.0f * maxf(w.offsetMin, std::fabs(f) / v.primary.field.lipschitz)
                            : w.globalEpsilon;
}

SDFT_HOST_DEVICE inline Vec3 normalAt(const DirectPixelView& v, Vec3 p) {
    const Vec3 n =
        estimateTapeNormal(v.primary.field, p, v.primary.normalSpacingMin, v.primary.normals);
    return length(n) > 0 ? n : Vec3(0, 1, 0);
}

// Ambient + Lambert + Blinn-Phong at a secondary hit on plastic, each light seen by
// vis(p, n, light, li, evaluations) -> [0, 1].
template <class Visibility>
SDFT_HOST_DEVICE inline Vec3 shadeDirect(const DirectPixelView& v, const WhittedPixelView& w,
                                         Vec3 p, Vec3 n, Vec3 d, const PixelMaterial& m,
                                         WhittedCounters& c, const Visibility& vis) {
    Vec3 color = v.ambient * m.color;
    for (int li = 0; li < v.lightCount; ++li) {
        const Light& light = v.lights[li];
        const LightDirection to = towardLight(light, p);
        if (dot(n, to.dir) <= 0) continue;
        float seen = 1;
        if (w.shadows.enabled && light.castShadows)
            seen = vis(p, n, light, li, c.shadowEvaluations);
        if (seen <= 0) continue;
        color += blinnPhong(m.color, m.diffuse, m.specular, maxf(m.shininess, 1.0f), n, to.dir, d) *
                 light.color * (to.scale * seen);
    }
    return color;
}

// Distance along d from origin (inside the scene's solid) to where the ray leaves it, and the
// field there; false if it never does. By a convex object's bound when one holds origin (§3.5).
SDFT_HOST_DEVICE inline bool exitDistance(const DirectPixelView& v, const WhittedPixelView& w,
                                          Vec3 origin, Vec3 d, float& dist, float& value,
                                          WhittedCounters& c) {
    const TapeView& field = v.primary.field;
    for (int i = 0; i < w.convexCount; ++i) {
        const ConvexView& obj = w.convex[i];
        if (!obj.bounds.contains(origin)) continue;
        const float f = evalTape(obj.tape, origin);
        ++c.evaluations;
        if (f >= 0) continue;
        float tFar = kInfinity;
        for (int a = 0; a < 3; ++a) {
            if (d[a] > 0) tFar = minf(tFar, (obj.bounds.hi[a] - origin[a]) / d[a]);
            if (d[a] < 0) tFar = minf(tFar, (obj.bounds.lo[a] - origin[a]) / d[a]);
        }
        const float margin = 1e-3f * length(obj.bounds.extent()) + 1e-6f;
        const float start = tFar + margin;
        const Vec3 q = origin + d * start;
        const TraceResult back = traceTapeRay(obj.tape, {{q, -d}, 0.0f, start}, w.secondary);
        c.evaluations += static_cast<uint32_t>(back.evaluations);
        if (!back.hit) break;  // rounding: march through the interior instead
        // The object's exit is the scene's only where no other object covers it.
        const float scene = evalTape(field, q - d * back.t) / field.lipschitz;
        ++c.evaluations;
        if (scene < back.value / obj.tape.lipschitz - 2 * w.secondary.tau) break;
        dist = maxf(0.0f, start - back.t);
        value = -back.value;
        return true;
    }
    SphereTraceState s;
    const float invL = 1.0f / field.lipschitz;
    const Bounds3 everywhere{Vec3(-kInfinity), Vec3(kInfinity)};
    sphereTraceBegin(s, {origin, d}, 0.0f, v.primary.maxDistance, everywhere, w.secondary);
    while (!s.done()) sphereTraceAdvance(s, -evalTape(field, s.queryPoint()), invL, w.secondary);
    c.evaluations += static_cast<uint32_t>(s.result.evaluations);
    if (!s.result.hit) return false;
    dist = s.result.t;
    value = s.result.value;
    return true;
}

// A bounded stack of pending rays; a push beyond kCapacity (a budget deeper than the stack was
// sized for, which directPixelUnsupported and the CPU renderer refuse) is dropped.
// The slots are left uninitialised (PendingRay's Vec3s would zero them: 2 KB per device thread,
// 16 KB per CPU hit, written for every shaded pixel).
template <int kCapacity>
struct RayStack {
    union Slot {
        PendingRay ray;
        SDFT_HOST_DEVICE Slot() {}
    };
    Slot slots[kCapacity];
    int top = 0;
    SDFT_HOST_DEVICE void push(const PendingRay& r) {
        if (top < kCapacity) slots[top++].ray = r;
    }
    SDFT_HOST_DEVICE PendingRay pop() { return slots[--top].ray; }
};

// The hit at p (unit normal n, field value f) of a ray along d with material m: plastic adds its
// direct light (each light seen by `vis`), a mirror or dielectric pushes its reflected and
// refracted rays.
template <class Stack, class Visibility>
SDFT_HOST_DEVICE inline void shadeHit(const DirectPixelView& v, const WhittedPixelView& w, Vec3 p,
                                      Vec3 n, float f, Vec3 d, const PixelMaterial& m, Vec3 weight,
                                      int reflections, int refractions, Vec3& radiance,
                                      Stack& stack, WhittedCounters& c, const Visibility& vis) {
    if (dot(n, d) > 0) n = -n;  // seen from behind (an open or thin surface)
    const float eps = offset(v, w, f);
    const int8_t refl = static_cast<int8_t>(reflections), refr = static_cast<int8_t>(refractions);
    if (m.kind == Material::Kind::Plastic) {
        radiance += weight * shadeDirect(v, w, p, n, d, m, c, vis);
    } else if (m.kind == Material::Kind::Mirror) {
        if (reflections > 0)
            stack.push({p + n * eps, reflect(d, n), weight * m.color, Vec3(0.0f), 1.0f, eps,
                        static_cast<int8_t>(refl - 1), refr, false});
    } else {
        const float cosI = -dot(d, n);
        const float r = fresnelDielectric(cosI, 1.0f, m.ior);
        Vec3 t;
        if (refractions > 0 && r < 1 && refract(d, n, 1.0f / m.ior, t))
            stack.push({p - n * eps, t, weight * (1 - r), m.absorption, m.ior, eps, refl,
                        static_cast<int8_t>(refr - 1), true});
        if (reflections > 0)
            stack.push({p + n * eps, reflect(d, n), weight * r, Vec3(0.0f), 1.0f, eps,
                        static_cast<int8_t>(refl - 1), refr, false});
    }
}

}  // namespace whitted_pixel

// Radiance leaving the mirror or dielectric hit p (unit normal n, field value f) against the unit
// ray direction d. Secondary hits on plastic see each light by vis(p, n, light, li, evaluations)
// (the CPU renderer's handles shadow maps; see the overload below); kStack: the stack's capacity
// (whittedStackFor the budget).
template <int kMaterialRegs, int kStack, class Visibility>
SDFT_HOST_DEVICE inline Vec3 shadeWhitted(const DirectPixelView& v, const WhittedPixelView& w,
                                          Vec3 p, Vec3 n, float f, Vec3 d, const PixelMaterial& m,
                                          WhittedCounters& c, const Visibility& vis) {
    using namespace whitted_pixel;
    Vec3 radiance(0.0f);
    RayStack<kStack> stack;
    shadeHit(v, w, p, n, f, d, m, Vec3(1.0f), w.maxReflections, w.maxRefractions, radiance, stack,
             c, vis);
    while (stack.top > 0) {
        const PendingRay r = stack.pop();
        ++c.rays;
        if (!r.inside) {
            TraceResult hit = traceTapeRay(
                v.primary.field, {{r.origin, r.dir}, 0.0f, v.primary.maxDistance}, w.secondary);
            c.evaluations += static_cast<uint32_t>(hit.evaluations);
            meetHorizon(v.primary.horizon, {r.origin, r.dir}, hit);  // the floor's far part
            if (!hit.hit) {
                radiance += r.weight * v.background;
                continue;
            }
            if (hit.t <= 2 * r.eps) ++c.selfIntersections;
            const Vec3 q = r.origin + r.dir * hit.t;
            const Vec3 nq = normalAt(v, q);
            const PixelMaterial mq = direct_pixel::materialAt<kMaterialRegs>(v, q, nq);
            shadeHit(v, w, q, nq, hit.value, r.dir, mq, r.weight, r.reflections, r.refractions,
                     radiance, stack, c, vis);
            continue;
        }
        // Inside a dielectric: the exit, attenuated, splits into the refracted ray out and the
        // internal reflection.
        float dist = 0, value = 0;
        if (!exitDistance(v, w, r.origin, r.dir, dist, value, c)) continue;
        if (dist <= 2 * r.eps) ++c.selfIntersections;
        const Vec3 att(expf(-r.absorption.x * dist), expf(-r.absorption.y * dist),
                       expf(-r.absorption.z * dist));
        const Vec3 q = r.origin + r.dir * dist;
        const Vec3 nOut = normalAt(v, q);  // the outward normal: d leaves along it
        const float e = offset(v, w, value);
        const float fr = fresnelDielectric(dot(r.dir, nOut), r.ior, 1.0f);
        const Vec3 weight = r.weight * att;
        if (r.refractions > 0)
            stack.push({q - nOut * e, reflect(r.dir, -nOut), weight * fr, r.absorption, r.ior, e,
                        r.reflections, static_cast<int8_t>(r.refractions - 1), true});
        Vec3 t;
        if (fr < 1 && refract(r.dir, -nOut, r.ior, t))
            stack.push({q + nOut * e, t, weight * (1 - fr), Vec3(0.0f), 1.0f, e, r.reflections,
                        r.refractions, false});
    }
    return radiance;
}

// The same, secondary hits seeing the lights by the settings' shadow method (secondaryVisibility),
// on a device thread's stack.
template <int kMaterialRegs>
SDFT_HOST_DEVICE inline Vec3 shadeWhitted(const DirectPixelView& v, const WhittedPixelView& w,
                                          Vec3 p, Vec3 n, float f, Vec3 d, const PixelMaterial& m,
                                          WhittedCounters& c) {
    const auto vis = [&](Vec3 q, Vec3 nq, const Light& light, int, uint32_t& evaluations) {
        return secondaryVisibility(v.primary.field, w.shadows, q, nq, light, evaluations);
    };
    return shadeWhitted<kMaterialRegs, kWhittedStack>(v, w, p, n, f, d, m, c, vis);
}

// One pixel, shaded: shadeDirectPixel, then Whitted rays where the hit is a mirror or dielectric
// (kWhitted: the plan has one; a plastic-only plan's kernel leaves them out).
template <int kMaterialRegs, bool kWhitted>
SDFT_HOST_DEVICE inline DirectPixel shadePixel(const DirectPixelView& v, const WhittedPixelView& w,
                                               int x, int y) {
    DirectPixel px = shadeDirectPixel<kMaterialRegs>(v, x, y);
    if (kWhitted && px.primary.trace.hit && px.material.kind != Material::Kind::Plastic) {
        const Ray ray = primaryRay(v.primary.camera, x, y, v.primary.jitter);
        WhittedCounters c;
        const Vec3 radiance = shadeWhitted<kMaterialRegs>(
            v, w, ray.at(px.primary.trace.t) + px.primary.normal * px.primary.bias,
            px.primary.normal, px.primary.trace.value, ray.direction, px.material, c);
        px.color = isFinite(radiance) ? radiance : Vec3(0.0f);
        px.secondaryRays = c.rays;
        px.secondaryEvaluations = c.evaluations;
        px.selfIntersections = c.selfIntersections;
        px.shadowEvaluations += c.shadowEvaluations;
    }
    return px;
}

// The host side of a Whitted view: the convex objects' tape views (valid while the plan lives).
struct WhittedPixelTables {
    std::vector<ConvexView> convex;
};
WhittedPixelTables whittedPixelTables(const RenderPlan& plan);
// The view of `plan`, its convex objects `tables`'s (a device replaces them with its copies).
WhittedPixelView whittedPixelView(const RenderPlan& plan, const WhittedPixelTables& tables);
// Whether `plan` has a mirror or dielectric material (the kernel needs Whitted rays).
bool planHasWhitted(const RenderPlan& plan);

}  // namespace sdft
