// Segment bounds (field/tape_segment.h) for many rays at once: the batch form of
// evalTapeSegment, a structure of arrays walked one instruction at a time like Tape::evalBatch,
// so segment tracing's packets of primary rays pay one interpreter pass per step, not one per ray.
// The same values, slopes and lengths as the scalar form (tested).
#pragma once

#include <cstdint>
#include <vector>

#include "sdftrace/field/tape.h"

namespace sdft {

// The rays of a batch: segment i starts at (x, y, z)[i] along the unit (ux, uy, uz)[i] for
// len[i]; the evaluator writes value[i], slope[i] and the length it holds on, len[i].
struct SegmentLanes {
    const float *x, *y, *z, *ux, *uy, *uz;
    float *len, *value, *slope;
};

// Registers and lane groups, one per thread, reused across calls.
struct SegmentBatchScratch {
    std::vector<float> points, velocities;  // numPointRegs * 3 * kBatchWidth each
    std::vector<float> scalars, slopes;     // numScalarRegs * kBatchWidth each
    std::vector<uint8_t> culled;            // numCulls * kBatchWidth
    std::vector<float> culledLen;           // numCulls * kBatchWidth
    std::vector<uint32_t> laneTape, order;
    std::vector<float> gathered;  // a group's lanes: 7 inputs and 3 outputs, kBatchWidth each
};

void evalSegmentBatch(const Tape& tape, const SegmentLanes& lanes, int n,
                      SegmentBatchScratch& scratch);

}  // namespace sdft
