// Whitted ray tracing (Whitted 1980) over distance bounds, as Keinert et al. 2014 §4 use it for
// their translucent scenes: mirrors reflect; dielectrics split into Fresnel-weighted reflection and
// refraction (Snell, total internal reflection, Beer-Lambert absorption inside); rays inside an
// object are sphere traced on -f to the exit. Each kind of bounce has its own budget (Keinert: 2
// reflections, 8 refractions); a ray out of budget is dark. Secondary rays start off the surface by
// Keinert §3.3's dynamic epsilon, 2 max(eps_min, |f(p)|), or by a global epsilon (selectable, to
// show the acne the global one gives when hits lie up to half a pixel from the surface).
//
// Keinert §3.5, convex objects in convex bounds: a refracted ray inside a convex object (a
// top-level object built from convex primitives by intersections and transforms) does not march
// through the interior; it jumps to where it leaves the object's bounding box and sphere traces
// back along -d on the object's own field, which finds the same exit point in fewer steps.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "sdftrace/field/tape.h"
#include "sdftrace/render/optics.h"
#include "sdftrace/render/render_plan.h"

namespace sdft {

struct WhittedStats {
    uint64_t rays = 0, evaluations = 0;
    // Secondary rays that struck the surface they left within twice their offset.
    uint64_t selfIntersections = 0;
    uint64_t shadowEvaluations = 0;  // of the secondary hits' shadow rays
};

class WhittedTracer {
  public:
    // How much of a light a point sees (the renderer's shadow method), adding the field
    // evaluations it took to `evaluations`.
    using Visibility = std::function<float(Vec3 p, Vec3 n, const Light& light, int lightIndex,
                                           uint64_t& evaluations)>;
    WhittedTracer(const RenderPlan& plan, Visibility visibility);

    // Radiance leaving a mirror or dielectric hit p (unit normal n, field value f) against the
    // unit ray direction d.
    Vec3 shadeSpecular(Vec3 p, Vec3 n, float f, Vec3 d, const Material& m,
                       WhittedStats& stats) const;

    // The material at p (the blend's heaviest kind, mixed colours).
    Material materialAt(Vec3 p, Vec3 n) const;

  private:
    Vec3 traceOutside(Vec3 origin, Vec3 d, int reflections, int refractions, float offset,
                      WhittedStats& stats) const;
    Vec3 traceInside(Vec3 origin, Vec3 d, const Material& m, int reflections, int refractions,
                     float offset, WhittedStats& stats) const;
    // Distance along d from origin (inside the scene's solid) to where the ray leaves it, and the
    // field there; false if it never does. By the convex bound when one holds origin.
    bool exitDistance(Vec3 origin, Vec3 d, float& dist, float& value, WhittedStats& stats) const;
    Vec3 shade(Vec3 p, Vec3 n, float f, Vec3 d, const Material& m, int reflections, int refractions,
               WhittedStats& stats) const;
    Vec3 shadeDirect(Vec3 p, Vec3 n, Vec3 d, const Material& m, WhittedStats& stats) const;
    float offset(float f) const;
    Vec3 normalAt(Vec3 p) const;

    const RenderPlan& m_plan;
    const Tape& m_tape;
    Visibility m_visibility;
    TraceOptions m_trace;
};

}  // namespace sdft
