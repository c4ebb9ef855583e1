// Ray tracing of a sparse block grid by two-level 3D-DDA (Jamriška 2010, §4): the coarse loop walks
// blocks and skips those flagged inside or outside; in a surface block the inner loop walks cells
// and tests only those whose bit in the block's mask is set (§4.1); a surface cell is intersected
// by the midpoint method or by false position with 1-4 iterations (§4.2). Shadow rays can use the
// volumetric-occluder traversal of §7. Dense grids are traversed as one block.
#pragma once

#include "sdftrace/field/grid.h"

namespace sdft {

enum class CellIntersection { Midpoint, FalsePosition };
enum class GridNormal { AnalyticTrilinear, DifferenceOfInterpolations, InterpolationOfDifferences };

struct GridTraceOptions {
    CellIntersection cellMethod = CellIntersection::FalsePosition;
    int falsiIters = 1;    // §4.2: 1 is visually the same as 4 (Jamriška Table 1)
    bool bitMasks = true;  // §4.1: test the precomputed mask instead of the 8 corner signs
    // traceGridRays: eight rays at a time in AVX2 registers (the same results; false: one by one)
    bool packets = true;
};

struct GridTraceResult {
    bool hit = false;
    float t = kInfinity;
    int traversalSteps = 0;     // blocks + cells visited (Jamriška fig. 6-7)
    int intersectionTests = 0;  // surface cells intersected
    int interpolations = 0;     // trilinear reconstructions
    // At a hit: the gradient of the trilinear reconstruction in the cell where the hit was found,
    // at t (grid units, not normalised; Jamriška §5's analytic estimator from the samples the test
    // already read). Zero without a hit.
    Vec3 gradient;
};

// First intersection of the ray with the zero level set on [tMin, tMax]. The ray's direction
// decides which crossing counts: the field's sign at the ray's start, looked up there unless
// startSign (+1 or -1) gives it. A caller that knows it saves that lookup: a camera's primary rays
// start at the eye, or where the min/max buffer (Jamriška §6) starts them, after no surface block,
// so every one has the eye's sign (gridSignAt).
GridTraceResult traceGridRay(const GridView& grid, const Ray& ray, float tMin, float tMax,
                             const GridTraceOptions& options, float startSign = 0);

// traceGridRay on each of n rays, out[i] for rays[i] on [tMin[i], tMax[i]] (an empty result where
// tMin[i] > tMax[i]). With AVX2, options.packets and a sparse grid's bit masks, eight rays at a
// time walk the DDA together in vector registers (trace/grid_packet.cpp): the same results and
// counters, faster on coherent rays (a tile's primary rays).
void traceGridRays(const GridView& grid, const Ray* rays, const float* tMin, const float* tMax,
                   int n, const GridTraceOptions& options, GridTraceResult* out,
                   float startSign = 0);

// The sign of the grid's reconstruction at p, as a ray starting there sees it: +1 outside the
// grid's box (a ray entering the box starts outside the solid), else +1 where the trilinear value
// is >= 0 and -1 below.
float gridSignAt(const GridView& grid, Vec3 p);

// Whether anything blocks the ray on [tMin, tMax]. With occluderThreshold > 0, Jamriška §7: walk
// only the coarse blocks, stopping at the first inside block; after the first surface block, give
// up after that many more blocks and restart the full traversal from it. 0 = plain traversal.
GridTraceResult traceGridShadow(const GridView& grid, const Ray& ray, float tMin, float tMax,
                                const GridTraceOptions& options, int occluderThreshold);

// Jamriška §5: the three gradient estimators, unit length (zero if degenerate).
Vec3 gridNormal(const GridView& grid, Vec3 p, GridNormal method);

// The normal at a hit p of a trace (`hit`): the analytic estimator from the hit's cell (the trace's
// gradient: no second lookup of the cell), the others as gridNormal at p.
Vec3 gridHitNormal(const GridView& grid, const GridTraceResult& hit, Vec3 p, GridNormal method);

}  // namespace sdft
