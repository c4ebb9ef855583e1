// Sphere tracing of a Lipschitz field (Hart 1996; Liktor 2008, §2.2) with the enhancements of
// Keinert et al. 2014 (§3.1 over-relaxation, §3.2 screen-space selection, §3.4 discontinuity
// reduction) and Liktor 2008 (§5.3-5.4 hybrid with regula falsi, fixed-step mode).
//
// Written as a per-ray state machine: the driver asks the state for its query point, evaluates the
// field there (alone, or in a batch with many other rays), and hands the value back to advance().
// One definition of the algorithm thus serves the scalar path and the batched path.
#pragma once

#include <cmath>
#include <cstdint>

#include "sdftrace/math/ray.h"
#include "sdftrace/trace/trace_options.h"

namespace sdft {

struct TraceResult {
    bool hit = false;
    float t = kInfinity;  // distance along the unit ray direction; +inf on a miss
    // f where the march placed the hit (Keinert fig. 9), before the root refinement moved t onto
    // f = 0: the error scale by which secondary rays leave the surface (Keinert §3.3's dynamic ε).
    float value = 0;
    int evaluations = 0;  // field evaluations spent on this ray
    int fallbacks = 0;    // over-relaxation fallbacks taken (Keinert Listing 2)
};

struct SphereTraceState {
    enum Phase : uint8_t { kMarch, kLinear, kFalsi, kRefine, kRoot, kDone };

    Ray ray;
    float tMax = 0;
    float t = 0;  // where the next evaluation happens
    float candidateT = 0, candidateError = kInfinity, candidateValue = 0;
    float previousRadius = 0, stepLength = 0, omega = 1, sign = 0;
    float tA = 0, fA = 0, tB = 0, fB = 0;  // hybrid and root refinement: the bracket
    // The march's latest samples on each side of the surface (values sign * f): the root
    // refinement's bracket or secant starts from them.
    float posT = 0, posV = 0, prevPosT = 0, prevPosV = 0, negT = 0, negV = 0;
    float hitT = 0, hitF = 0;   // the placement the march chose (kept when no root is near)
    float segment = kInfinity;  // segment tracing: the segment the next march sample bounds
    int steps = 0, refineLeft = 0;
    uint8_t samples = 0;  // bit 0: pos valid, bit 1: prevPos valid, bit 2: neg valid
    bool bracketed = false;
    int8_t sameSide = 0;  // Illinois: +1 / -1 after a falsi step that kept the other end
    Phase phase = kMarch;
    TraceResult result;

    SDFT_HOST_DEVICE bool done() const { return phase == kDone; }
    SDFT_HOST_DEVICE Vec3 queryPoint() const { return ray.at(t); }
};

// Starts a ray on [tMin, tMax] clipped to `bounds`; a ray that misses the bounds is done at once.
SDFT_HOST_DEVICE inline void sphereTraceBegin(SphereTraceState& s, const Ray& ray, float tMin,
                                              float tMax, const Bounds3& bounds,
                                              const TraceOptions& o) {
    s = SphereTraceState{};
    s.ray = ray;
    float t0, t1;
    if (!intersectBounds(bounds, ray, tMin, tMax, t0, t1)) {
        s.phase = SphereTraceState::kDone;
        return;
    }
    s.t = t0;
    s.tMax = t1;
    s.candidateT = t0;
    s.omega = o.omega;
    // The bounds contain the whole solid, so a ray clipped to them starts outside it (its first
    // sample may sit exactly on a tight surface, where f rounds to -0). Otherwise the sign of the
    // first sample decides (Keinert Listing 2's functionSign).
    if (t0 > tMin) s.sign = 1.0f;
}

namespace detail {

SDFT_HOST_DEVICE inline float hitError(const SphereTraceState& s, float radius,
                                       const TraceOptions& o) {
    return o.screenSpace ? radius / maxf(s.t, 1e-6f) : radius;
}
SDFT_HOST_DEVICE inline float hitThreshold(const TraceOptions& o) {
    return o.screenSpace ? o.pixelRadius : o.tau;
}
// The permitted error err(t) the discontinuity reduction aims f at (Keinert eq. 2).
SDFT_HOST_DEVICE inline float permittedError(float t, const TraceOptions& o) {
    return o.screenSpace ? t * o.pixelRadius : o.tau;
}

// Keinert et al. 2014, §3.4, eq. 3: the discontinuity reduction's move from the sample at s.t,
// whose value is f: p_{i+1} = p_i + d (f(p_i) - err(|p_i - o|)).
SDFT_HOST_DEVICE inline float discontinuityMove(const SphereTraceState& s, float f, float invL,
                                                const TraceOptions& o) {
    return s.t + s.sign * f * invL - permittedError(s.t, o);
}

SDFT_HOST_DEVICE inline void finish(SphereTraceState& s, bool hit, float t, float value) {
    s.result.hit = hit;
    s.result.t = hit ? t : kInfinity;
    s.result.value = hit ? value : 0.0f;
    s.phase = SphereTraceState::kDone;
}

// Remembers a sample of the march (v = sign * f) on its side of the surface.
SDFT_HOST_DEVICE inline void recordSample(SphereTraceState& s, float t, float v) {
    if (v > 0) {
        if (s.samples & 1u) {
            s.prevPosT = s.posT;
            s.prevPosV = s.posV;
            s.samples |= 2u;
        }
        s.posT = t;
        s.posV = v;
        s.samples |= 1u;
    } else {
        s.negT = t;
        s.negV = v;
        s.samples |= 4u;
    }
}

SDFT_HOST_DEVICE inline float falsiPoint(const SphereTraceState& s) {
    const float t = s.tA - s.fA * (s.tB - s.tA) / (s.fB - s.fA);
    return minf(maxf(t, minf(s.tA, s.tB)), maxf(s.tA, s.tB));
}

// The next probe of the root refinement: regula falsi inside a bracket; otherwise a secant step
// from the last two samples approaching the surface, at least the safe sphere step fA / L and at
// most kReach of them (a probe never jumps far along a grazing ray), a little long so that it
// brackets the root of a surface that curves away.
SDFT_HOST_DEVICE inline float rootProbe(const SphereTraceState& s, float prevT, float prevV,
                                        bool havePrev, float invL) {
    if (s.bracketed) return falsiPoint(s);
    constexpr float kReach = 16.0f, kLong = 1.0f + 1.0f / 32.0f;
    const float safe = s.fA * invL;
    float step = safe;
    // The other sample may lie on either side of tA (the discontinuity reduction steps back);
    // only a slope that approaches the surface says where the root is.
    const float slope = havePrev && prevT != s.tA ? (prevV - s.fA) / (s.tA - prevT) : 0.0f;
    if (slope > 0) step = kLong * s.fA / slope;
    return s.tA + minf(maxf(step, safe), kReach * safe);
}

// Starts the root refinement at the hit the march chose, (t, f); finishes there when refinement
// is off, the point is on the surface, or no sample brackets it from the inside.
SDFT_HOST_DEVICE inline void beginRoot(SphereTraceState& s, float t, float f, float invL,
                                       const TraceOptions& o) {
    const float v = s.sign * f;
    if (o.rootIters <= 0 || v == 0 || !(t < kInfinity)) {
        finish(s, true, t, f);
        return;
    }
    s.hitT = t;
    s.hitF = f;
    s.sameSide = 0;
    if (v < 0) {
        // The march crossed the surface (an over-relaxed step, or the discontinuity reduction):
        // the latest sample before it in front of the surface closes the bracket.
        if (!(s.samples & 1u) || s.posT >= t) {
            finish(s, true, t, f);
            return;
        }
        s.tA = s.posT;
        s.fA = s.posV;
        s.tB = t;
        s.fB = v;
        s.bracketed = true;
    } else {
        s.tA = t;
        s.fA = v;
        s.bracketed = (s.samples & 4u) && s.negT > t && s.negT - t <= 16.0f * v * invL;
        if (s.bracketed) {
            s.tB = s.negT;
            s.fB = s.negV;
        }
    }
    s.phase = SphereTraceState::kRoot;
    s.refineLeft = o.rootIters;
    // The secant's other sample: the latest one in front of the surface other than the hit
    // itself (usually the latest sample).
    bool prev = false;
    if ((s.samples & 1u) && s.posT != t) {
        s.prevPosT = s.posT;
        s.prevPosV = s.posV;
        prev = true;
    } else {
        prev = (s.samples & 2u) && s.prevPosT != t;
    }
    s.samples = prev ? 2u : 0u;
    s.t = rootProbe(s, s.prevPosT, s.prevPosV, prev, invL);
}

// One evaluation of the root refinement; after the last one a bracketed root is placed by regula
// falsi without evaluating it. A hit whose probes found no sign change keeps the march's placement
// (a near miss at a silhouette is not pulled along the ray) unless a probe all but touched f = 0.
SDFT_HOST_DEVICE inline void rootStep(SphereTraceState& s, float f, float invL) {
    constexpr float kOnSurface = 1e-5f;
    const float v = s.sign * f;
    const float t = s.t;
    if (v == 0) {
        finish(s, true, t, s.hitF);
        return;
    }
    if (s.bracketed) {
        // Illinois: halve the value of an end kept twice, so both ends converge.
        if (v > 0) {
            s.tA = t;
            s.fA = v;
            if (s.sameSide == 1) s.fB *= 0.5f;
            s.sameSide = 1;
        } else {
            s.tB = t;
            s.fB = v;
            if (s.sameSide == -1) s.fA *= 0.5f;
            s.sameSide = -1;
        }
    } else if (v < 0) {
        s.tB = t;
        s.fB = v;
        s.bracketed = true;
    } else if (v < s.fA) {
        s.prevPosT = s.tA;
        s.prevPosV = s.fA;
        s.samples = 2u;
        s.tA = t;
        s.fA = v;
    } else {
        // Moving away from the surface: no root near the chosen point.
        s.refineLeft = 0;
    }
    if (--s.refineLeft <= 0) {
        if (s.bracketed) {
            finish(s, true, falsiPoint(s), s.hitF);
        } else {
            // No sign change: a probe that came within 1e-5 t of the surface (far below what
            // a pixel resolves) is a hit at grazing incidence; otherwise the march's placement.
            const bool onSurface = s.fA * invL <= kOnSurface * s.tA;
            finish(s, true, onSurface ? s.tA : s.hitT, s.hitF);
        }
        return;
    }
    s.t = rootProbe(s, s.prevPosT, s.prevPosV, s.samples & 2u, invL);
}

// End of the march: decide hit or miss (Keinert Listing 2, last lines), then refine.
SDFT_HOST_DEVICE inline void endMarch(SphereTraceState& s, float invL, const TraceOptions& o) {
    bool hit = s.candidateError <= hitThreshold(o) && s.candidateT <= s.tMax;
    if (!hit && !o.forceHit) {
        finish(s, false, 0, 0);
        return;
    }
    if (o.discontinuityIters > 0) {
        // n moves, then one evaluation for f(p_n). The first move starts from the march's own
        // sample at the candidate, whose value is known: it is recorded again, as an evaluation
        // there would have been, and the move made without one.
        s.phase = SphereTraceState::kRefine;
        s.refineLeft = o.discontinuityIters + 1;
        s.t = s.candidateT;
        if (s.candidateError < kInfinity) {
            recordSample(s, s.t, s.sign * s.candidateValue);
            --s.refineLeft;
            s.t = discontinuityMove(s, s.candidateValue, invL, o);
        }
        return;
    }
    beginRoot(s, s.candidateT, s.candidateValue, invL, o);
}

// An over-relaxation's choice at a march sample: the move to the next sample, and whether this
// sample is abandoned (its unbounding sphere does not overlap the previous one).
struct RelaxedStep {
    float move;
    bool abandoned;
};

// Keinert et al. 2014, §3.1 and Listing 2: the fixed factor omega with its fallback.
SDFT_HOST_DEVICE inline RelaxedStep fixedRelaxation(SphereTraceState& s, float signedRadius,
                                                    float radius) {
    const bool sorFail = s.omega > 1 && (radius + s.previousRadius) < s.stepLength;
    if (sorFail) {
        // The unbounding spheres do not overlap: step back to where plain sphere tracing would
        // have gone (p_fallback) and continue without over-relaxation.
        s.stepLength -= s.omega * s.stepLength;
        s.omega = 1;
        s.result.fallbacks++;
    } else {
        s.stepLength = signedRadius * s.omega;
    }
    s.previousRadius = radius;
    return {s.stepLength, sorFail};
}

// Bálint & Valasek 2018: with the unbounding radius falling at slope s per unit of t (the last two
// samples; s = cos of the angle to a plane), a step d keeps the next sphere, r - s d, overlapping
// this one while d <= 2 r / (1 + s): twice the plain step along a grazing plane, the plain step
// (onto the plane) head on. A step that proves too long (the spheres do not overlap: the surface
// curved towards the ray) falls back to the plain step from the previous sample, so no surface is
// ever stepped over; the next step starts a fresh slope. stepLength is the distance from the
// reference sample (previousRadius's) to the next one; only a step longer than plain can fail
// the overlap test, since radius >= 0.
SDFT_HOST_DEVICE inline RelaxedStep adaptiveRelaxation(SphereTraceState& s, float signedRadius,
                                                       float radius) {
    // A margin under the planar bound (surfaces that curve towards the ray fall back less often)
    // and a cap on the factor (rays leaving a surface). Chosen on the tracer benchmark's scenes:
    // 0.9 and 2 need fewer evaluations than 0.8-1.0 and 1.6-8 (docs/performance.md).
    constexpr float kGain = 0.9f, kMaxOmega = 2.0f;
    if (radius + s.previousRadius < s.stepLength) {
        const float back = s.previousRadius - s.stepLength;
        s.stepLength = s.previousRadius;  // from the previous sample, which stays the reference
        s.result.fallbacks++;
        return {back, true};
    }
    float omega = 1;  // the first step has no slope yet
    if (s.stepLength > 0 && signedRadius > 0) {
        const float slope = minf((s.previousRadius - radius) / s.stepLength, 1.0f);
        omega = slope <= 0 ? kMaxOmega : minf(1 + kGain * (2 / (1 + slope) - 1), kMaxOmega);
    }
    s.stepLength = signedRadius * omega;
    s.previousRadius = radius;
    return {s.stepLength, false};
}

// Galin et al. 2020, §3 (Algorithm 2): with |f(t + x) - f(t)| <= slope x on the segment
// [t, t + length] ahead, a step of |f| / slope cannot cross the surface, up to the segment's end;
// never shorter than the plain step |f| / L. The next segment is kGrowth times the step (their
// kappa): long enough to allow a longer step, short enough that its slope stays tight.
SDFT_HOST_DEVICE inline RelaxedStep segmentStep(SphereTraceState& s, float f, float signedRadius,
                                                float radius, float slope, float length) {
    constexpr float kGrowth = 2.0f;
    float move = signedRadius;
    if (signedRadius > 0) {
        const float ahead = slope > 0 ? std::fabs(f) / slope : kInfinity;
        move = maxf(radius, minf(ahead, length));
    }
    s.segment = kGrowth * std::fabs(move);
    s.stepLength = move;
    s.previousRadius = radius;
    return {move, false};
}

// Keinert et al. 2014, Listing 2: one march step, over-relaxed (the fixed factor of §3.1, or
// Bálint & Valasek's adaptive one) with the safe fallback, and screen-space intersection-point
// selection (§3.2); or, given the slope of f along the segment ahead (slope >= 0), a step of
// segment tracing (Galin et al. 2020).
SDFT_HOST_DEVICE inline void marchStep(SphereTraceState& s, float f, float invL,
                                       const TraceOptions& o, float slope, float length) {
    if (s.sign == 0) s.sign = f < 0 ? -1.0f : 1.0f;  // a ray starting inside traces out
    float signedRadius = s.sign * f * invL;
    float radius = std::fabs(signedRadius);
    const RelaxedStep step = slope >= 0 ? segmentStep(s, f, signedRadius, radius, slope, length)
                             : o.adaptiveRelaxation ? adaptiveRelaxation(s, signedRadius, radius)
                                                    : fixedRelaxation(s, signedRadius, radius);
    const bool sorFail = step.abandoned;
    float error = hitError(s, radius, o);
    if (!sorFail && error < s.candidateError && s.t <= s.tMax) {
        s.candidateT = s.t;
        s.candidateError = error;
        s.candidateValue = f;
    }
    s.steps++;
    if (o.hybrid && !sorFail && radius < o.hybridEpsilon) {
        // Liktor 2008, §5.4: near the surface, linear search takes larger steps than sphere
        // tracing.
        s.phase = SphereTraceState::kLinear;
        s.tA = s.t;
        s.fA = signedRadius;
        s.t += o.hybridStep;
        if (s.t > s.tMax || s.steps >= o.maxSteps) finish(s, false, 0, 0);
        return;
    }
    bool converged = !o.hybrid && !sorFail && error < hitThreshold(o);
    // An abandoned sample beyond tMax does not end the ray: the fallback steps back.
    const bool beyond = s.t > s.tMax && !sorFail;
    if ((converged && !o.fixedSteps) || (beyond && !o.fixedSteps) || s.steps >= o.maxSteps) {
        if (o.hybrid) {
            finish(s, false, 0, 0);
        } else {
            endMarch(s, invL, o);
        }
        return;
    }
    s.t += step.move;
}

// Liktor 2008, §5.3: fixed steps until the sign changes, then regula falsi on the bracket.
SDFT_HOST_DEVICE inline void linearStep(SphereTraceState& s, float f, float invL,
                                        const TraceOptions& o) {
    float v = s.sign * f * invL;
    s.steps++;
    if (v < 0) {
        s.tB = s.t;
        s.fB = v;
        s.phase = SphereTraceState::kFalsi;
        s.refineLeft = o.falsiIters;
        if (s.refineLeft <= 0) {
            finish(s, true, s.tB, f);
            return;
        }
        s.t = s.tA - s.fA * (s.tB - s.tA) / (s.fB - s.fA);
        return;
    }
    if (v > 2 * o.hybridEpsilon) {
        // The ray moves away from the surface again: back to sphere tracing.
        s.phase = SphereTraceState::kMarch;
        s.previousRadius = 0;
        s.stepLength = 0;
        s.t += v;
    } else {
        s.tA = s.t;
        s.fA = v;
        s.t += o.hybridStep;
    }
    if (s.t > s.tMax || s.steps >= o.maxSteps) finish(s, false, 0, 0);
}

SDFT_HOST_DEVICE inline void falsiStep(SphereTraceState& s, float f, float invL) {
    float v = s.sign * f * invL;
    if (v > 0) {
        s.tA = s.t;
        s.fA = v;
    } else {
        s.tB = s.t;
        s.fB = v;
    }
    if (--s.refineLeft <= 0 || v == 0) {
        finish(s, true, s.t, f);
        return;
    }
    s.t = s.tA - s.fA * (s.tB - s.tA) / (s.fB - s.fA);
}

// One iteration of the discontinuity reduction (Keinert §3.4) on f(p_i).
SDFT_HOST_DEVICE inline void refineStep(SphereTraceState& s, float f, float invL,
                                        const TraceOptions& o) {
    const float next = discontinuityMove(s, f, invL, o);
    if (--s.refineLeft <= 0) {
        beginRoot(s, s.t, f, invL, o);
        return;
    }
    s.t = next;
}

}  // namespace detail

// Whether the next evaluation should also bound the field's slope along the ray (segment
// tracing), and over how long a segment from the query point.
SDFT_HOST_DEVICE inline bool sphereTraceWantsSegment(const SphereTraceState& s,
                                                     const TraceOptions& o) {
    return o.segmentTracing && s.phase == SphereTraceState::kMarch;
}
SDFT_HOST_DEVICE inline float sphereTraceSegment(const SphereTraceState& s) {
    return maxf(minf(s.segment, s.tMax - s.t), 0.0f);
}

// Consumes f(queryPoint()) and moves the state on. invL = 1 / Lipschitz bound of the field.
// With segment tracing, slope >= 0 bounds |df/dt| on [t, t + length] (sphereTraceSegment's
// segment, or a shorter one); a negative slope: none, the plain or over-relaxed step.
SDFT_HOST_DEVICE inline void sphereTraceAdvance(SphereTraceState& s, float f, float invL,
                                                const TraceOptions& o, float slope = -1,
                                                float length = 0) {
    s.result.evaluations++;
    if (s.phase != SphereTraceState::kRoot) {
        // The sign is set by the first march step; until then every value counts as in front.
        const float v = s.sign == 0 ? std::fabs(f) : s.sign * f;
        detail::recordSample(s, s.t, v);
    }
    switch (s.phase) {
        case SphereTraceState::kMarch:
            detail::marchStep(s, f, invL, o, slope, length);
            break;
        case SphereTraceState::kLinear:
            detail::linearStep(s, f, invL, o);
            break;
        case SphereTraceState::kFalsi:
            detail::falsiStep(s, f, invL);
            break;
        case SphereTraceState::kRefine:
            detail::refineStep(s, f, invL, o);
            break;
        case SphereTraceState::kRoot:
            detail::rootStep(s, f, invL);
            break;
        case SphereTraceState::kDone:
            break;
    }
}

}  // namespace sdft
