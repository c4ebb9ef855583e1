// Switches of the analytic sphere tracer. Defaults are the best-quality settings; every enhancement
// can be turned off to measure it against the plain method.
#pragma once

#include "sdftrace/core/macros.h"

namespace sdft {

struct TraceOptions {
    int maxSteps = 256;  // field evaluations spent marching (Hart's MAX_ITERATIONS)
    float tau = 1e-3f;   // hit threshold on f/L when not using the screen-space criterion
    // Keinert et al. 2014, §3.1: step omega * f/L, with the safe fallback of Listing 2. 1 = off.
    // Used when adaptiveRelaxation is off.
    float omega = 1.2f;
    // Bálint & Valasek 2018 ("Accelerating Sphere Tracing"), the adaptive over-relaxation
    // Keinert §5 leaves to future work: each step's factor from the slope of the last two
    // unbounding radii, as long as the next sphere would still overlap this one were the surface
    // a plane; Keinert's overlap test and fallback keep it safe. Replaces the fixed omega.
    bool adaptiveRelaxation = false;
    // Galin et al. 2020 ("Segment Tracing Using Local Lipschitz Bounds"), primary rays: every
    // march sample also bounds the field's slope along the segment ahead (field/tape_segment.h),
    // and the ray steps |f| / slope, at most to the segment's end and at least the plain step; the
    // next segment is twice the step. Replaces the over-relaxation (fixed or adaptive) of the
    // march when on.
    bool segmentTracing = false;
    // Keinert et al. 2014, §3.2: pick the point with the smallest screen-space unbounding radius
    // and stop once it is under half a pixel. Needs pixelRadius (radius of a pixel at t = 1).
    bool screenSpace = true;
    float pixelRadius = 0;
    bool forceHit = false;  // return the best candidate even when it never converged
    // Keinert et al. 2014, §3.4: fixed-point iterations p += d (f(p) - err(t)) after the march.
    int discontinuityIters = 3;
    // Liktor 2008, §5.4: every ray takes exactly maxSteps march steps (no early exit).
    bool fixedSteps = false;
    // Liktor 2008, §5.3-5.4: sphere tracing until f/L < hybridEpsilon, then linear search with
    // step hybridStep until the sign changes, then falsiIters steps of regula falsi.
    bool hybrid = false;
    float hybridEpsilon = 0.02f;
    float hybridStep = 0.01f;
    int falsiIters = 4;
    // Evaluations spent moving the chosen hit onto the root of f (a secant step that brackets it,
    // then Illinois regula falsi; the last placement is interpolated, not evaluated). The march
    // still decides hit or miss and where to stop; a hit with no root near keeps its placement.
    // 0 = off (hits stay on Keinert's error level set, or at f/L < tau).
    int rootIters = 2;

    // The options of a ray without a pixel footprint of its own (shadow, reflection, refraction,
    // shadow-map and path rays): the primary rays' march and fixed relaxation, a plain threshold,
    // no screen-space selection, no refinement, no fixed step count. These rays start on a surface
    // (refracted ones inside it), where the adaptive factor's first slopes mislead it (it falls
    // back about as often as it saves), so they keep the fixed omega; and they are traced one by
    // one, where a segment bound costs 3-4 plain evaluations, more than it saves on them, so they
    // do not segment-trace.
    SDFT_HOST_DEVICE TraceOptions secondary() const {
        TraceOptions o = *this;
        o.adaptiveRelaxation = false;
        o.segmentTracing = false;
        o.screenSpace = false;
        o.forceHit = false;
        o.discontinuityIters = 0;
        o.fixedSteps = false;
        return o;
    }

    // The options of a ray asked only whether something is in the way (shadow rays): no root
    // refinement either.
    SDFT_HOST_DEVICE TraceOptions occlusion() const {
        TraceOptions o = secondary();
        o.rootIters = 0;
        return o;
    }

    // The plain method of Hart 1996 (Keinert Listing 1): no enhancement at all.
    SDFT_HOST_DEVICE static TraceOptions classic() {
        TraceOptions o;
        o.omega = 1;
        o.adaptiveRelaxation = false;
        o.segmentTracing = false;
        o.screenSpace = false;
        o.discontinuityIters = 0;
        return o;
    }
};

}  // namespace sdft
