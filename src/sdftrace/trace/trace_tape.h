// One ray sphere traced through a tape's view (field/tape_view.h): the state machine of
// trace/sphere_tracer.h driven by the scalar evaluator, one evaluation per step. The CPU's
// reference path (traceRay) and a device's per-thread tracing are this one function.
#pragma once

#include "sdftrace/core/macros.h"
#include "sdftrace/field/tape_segment.h"
#include "sdftrace/field/tape_view.h"
#include "sdftrace/math/ray.h"
#include "sdftrace/trace/sphere_tracer.h"

namespace sdft {

struct RaySegment {
    Ray ray;
    float tMin = 0;
    float tMax = kInfinity;
};

// One evaluation of a ray's march: the value, and with segment tracing its slope ahead.
SDFT_HOST_DEVICE inline void traceTapeStep(const TapeView& tape, SphereTraceState& s, float invL,
                                           const TraceOptions& o) {
    if (sphereTraceWantsSegment(s, o)) {
        const SegmentBound b =
            evalTapeSegment(tape, s.queryPoint(), s.ray.direction, sphereTraceSegment(s));
        sphereTraceAdvance(s, b.value, invL, o, b.slope, b.length);
    } else {
        sphereTraceAdvance(s, evalTape(tape, s.queryPoint()), invL, o);
    }
}

SDFT_HOST_DEVICE inline TraceResult traceTapeRay(const TapeView& tape, const RaySegment& seg,
                                                 const TraceOptions& o) {
    SphereTraceState s;
    const float invL = 1.0f / tape.lipschitz;
    sphereTraceBegin(s, seg.ray, seg.tMin, seg.tMax, tape.bounds, o);
    while (!s.done()) traceTapeStep(tape, s, invL, o);
    return s.result;
}

}  // namespace sdft
