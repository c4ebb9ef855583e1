// Drivers of the sphere-tracing state machine over a compiled tape: one ray at a time (the scalar
// reference path) or a packet of rays whose query points are evaluated in one batch per step.
#pragma once

#include <span>
#include <vector>

#include "sdftrace/field/tape.h"
#include "sdftrace/field/tape_segment_batch.h"
#include "sdftrace/trace/sphere_tracer.h"
#include "sdftrace/trace/trace_tape.h"

namespace sdft {

TraceResult traceRay(const Tape& tape, const RaySegment& segment, const TraceOptions& options);

// Per-thread buffers for tracePacket, reused across calls.
struct PacketScratch {
    std::vector<SphereTraceState> states;
    std::vector<int> active;
    std::vector<float> x, y, z, f;
    BatchScratch batch;
    // Segment tracing: the marching rays' directions, segments and slopes.
    std::vector<float> ux, uy, uz, len, slope;
    SegmentBatchScratch segment;
};

// Traces every segment; results[i] belongs to segments[i]. Same answers as traceRay.
void tracePacket(const Tape& tape, std::span<const RaySegment> segments,
                 const TraceOptions& options, std::span<TraceResult> results,
                 PacketScratch& scratch);

}  // namespace sdft
