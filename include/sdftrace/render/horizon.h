// Infinite planes seen to the horizon (not in the papers). Sphere tracing reaches a plane's far
// part only within t_max and a step budget: at grazing angles each step closes a fraction sin θ of
// the height, so a floor ended in a curved edge where the automatic t_max cut it. The planes that
// are children of the scene's top-level union are intersected analytically where a ray has left
// the bounds of everything else, beyond which nothing but those planes lies.
#pragma once

#include "sdftrace/core/macros.h"
#include "sdftrace/field/node.h"
#include "sdftrace/math/ray.h"
#include "sdftrace/trace/sphere_tracer.h"

namespace sdft {

struct HorizonPlanes {
    static constexpr int kMax = 4;
    int count = 0;
    float plane[kMax][4] = {};  // unit normal and offset: the solid is n.p + d <= 0
    Bounds3 rest;               // bounds of the scene without those planes (empty: nothing)
};

// The top-level planes of `root` (its own kind Plane, or its union's children of that kind, at
// most kMax) and the bounds of the rest; none where the rest is unbounded too, or where planes
// are more than kMax.
HorizonPlanes horizonPlanes(const NodePtr& root);

// The first plane `ray` meets beyond where it leaves h.rest, into t; false where there is none,
// where the ray starts inside a plane's solid (the march sees it there) or where a plane is met
// before the ray leaves h.rest (the march decides what lies in front).
SDFT_HOST_DEVICE inline bool horizonHit(const HorizonPlanes& h, const Ray& ray, float& t) {
    if (h.count == 0) return false;
    float t0 = 0, leave = 0;
    if (!h.rest.empty() && !intersectBounds(h.rest, ray, 0.0f, kInfinity, t0, leave)) leave = 0;
    float best = kInfinity;
    for (int i = 0; i < h.count; ++i) {
        const float* k = h.plane[i];
        const float f0 = ray.origin.x * k[0] + ray.origin.y * k[1] + ray.origin.z * k[2] + k[3];
        const float slope =
            ray.direction.x * k[0] + ray.direction.y * k[1] + ray.direction.z * k[2];
        if (!(f0 > 0)) return false;
        if (slope < 0) best = minf(best, f0 / -slope);
    }
    if (!(best < kInfinity) || best < leave) return false;
    t = best;
    return true;
}

// A march's miss `r` along `ray` made a hit on the plane it meets past the rest (horizonHit),
// where there is one: what every caller does with a ray that may leave the scene.
SDFT_HOST_DEVICE inline void meetHorizon(const HorizonPlanes& h, const Ray& ray, TraceResult& r) {
    if (!r.hit && horizonHit(h, ray, r.t)) {
        r.hit = true;
        r.value = 0;
    }
}

}  // namespace sdft
