// One pixel's primary ray through the plan's field and the normal at its hit: what the CPU
// renderer's tile loop does for a packet of pixels (tracePrimary, then stencilNormals), as one
// function a device thread runs for its pixel. The enhanced sphere tracer of Keinert et al. 2014
// (§3.1 over-relaxation, §3.2 screen-space hit selection with the camera's pixel footprint, §3.4
// discontinuity reduction) and the root refinement come from trace/sphere_tracer.h unchanged.
#pragma once

#include "sdftrace/core/macros.h"
#include "sdftrace/field/tape_view.h"
#include "sdftrace/math/camera.h"
#include "sdftrace/render/horizon.h"
#include "sdftrace/render/mesh_primary.h"
#include "sdftrace/render/normal_stencil.h"
#include "sdftrace/trace/grid_dda.h"
#include "sdftrace/trace/minmax_buffer.h"
#include "sdftrace/trace/trace_tape.h"

namespace sdft {

struct RenderPlan;
struct FrameView;

// Plain data: a kernel takes it by value.
struct PrimaryPixelView {
    TapeView field;  // the whole field: normals (and shading, shadows, secondary rays)
    // RTSDF's hybrid mode (RenderSettings::primaryTriangles): primary rays trace `primaryField`
    // (the field without the meshes; none when the scene is only meshes) and the meshes'
    // triangles, the nearer hit winning. Without meshes primaryField is `field`.
    TapeView primaryField;
    bool meshesOnly = false;
    MeshPrimaryView meshes;
    Camera camera{CameraDesc{}};
    TraceOptions options;  // the plan's primary-ray options, pixelRadius set from the camera
    float maxDistance = kInfinity;
    // The top-level infinite planes, met analytically past everything else (horizon.h): primary
    // rays and every secondary ray that leaves the scene see them to the horizon.
    HorizonPlanes horizon;
    float normalSpacingMin = 1e-4f;  // RenderSettings::normalSpacingMin
    float jitter[2] = {0, 0};
    NormalEstimator normals = NormalEstimator::Tetrahedral;
    // A lone grid traced by Jamriška's two-level DDA (§4) instead of sphere tracing: its index in
    // field.grids, -1 for none; the cell intersection and bit masks, and the gradient estimator
    // of §5 for its normals.
    int ddaGrid = -1;
    GridTraceOptions gridTrace;
    // The grid's sign at the camera's eye (gridSignAt): every primary ray's sign at its start, as
    // no surface block lies before it (traceGridRay's startSign).
    float gridStartSign = 0;
    GridNormal gridNormals = GridNormal::InterpolationOfDifferences;
    // The DDA's primary rays narrowed to their min/max-buffer interval (Jamriška §6), where the
    // caller built one for this frame's camera (primaryMinMax); none: the whole ray.
    MinMaxView minMax;
};

struct PrimaryPixel {
    TraceResult trace;     // DDA: evaluations are trilinear reconstructions, value f at the hit
    Vec3 normal{0, 0, 0};  // unit on a hit (facing the viewer where the gradient vanishes)
    int traversalSteps = 0, intersectionTests = 0;  // DDA: blocks + cells visited, cells tested
    // A triangle hit (hybrid mode): the normal is the triangle's, and the shading point lies
    // `bias` off it along the normal (MeshPrimaryHit::bias); 0 elsewhere.
    float bias = 0;
};

// The primary ray of pixel (x, y): through (x + 0.5 + jx, y + 0.5 + jy) (FrameView's jitter).
SDFT_HOST_DEVICE inline Ray primaryRay(const Camera& camera, int x, int y, const float jitter[2]) {
    return camera.rayThrough(x + 0.5f + jitter[0], y + 0.5f + jitter[1]);
}

SDFT_HOST_DEVICE inline PrimaryPixel tracePrimaryPixel(const PrimaryPixelView& v, int x, int y) {
    PrimaryPixel out;
    const RaySegment seg{primaryRay(v.camera, x, y, v.jitter), 0.0f, v.maxDistance};
    if (v.ddaGrid >= 0) {
        const GridView& g = v.field.grids[v.ddaGrid];
        float t0, t1;
        v.minMax.range(x, y, t0, t1);
        const float tMin = fmaxf(seg.tMin, t0), tMax = fminf(seg.tMax, t1);
        if (!(tMin <= tMax)) return out;  // no surface block projects here: a miss
        const GridTraceResult r =
            grid_dda::traceRay(g, seg.ray, tMin, tMax, v.gridTrace, v.gridStartSign);
        out.trace.hit = r.hit;
        out.trace.t = r.t;
        out.trace.evaluations = r.interpolations;
        out.traversalSteps = r.traversalSteps;
        out.intersectionTests = r.intersectionTests;
        if (r.hit) {
            const Vec3 p = seg.ray.at(r.t);
            out.trace.value = g.interpolate(p);
            out.normal =
                normalOrFacing(grid_dda::hitNormal(g, r, p, v.gridNormals), seg.ray.direction);
        }
        return out;
    }
    if (!v.meshesOnly) out.trace = traceTapeRay(v.primaryField, seg, v.options);
    meetHorizon(v.horizon, seg.ray, out.trace);
    if (v.meshes.count > 0) {
        const float tMax = out.trace.hit ? out.trace.t : seg.tMax;
        const MeshPrimaryHit h = meshPrimaryHit(v.meshes, seg.ray, tMax);
        if (h.t < tMax) {
            out.trace.hit = true;
            out.trace.t = h.t;
            out.trace.value = 0;
            out.normal = h.normal;
            out.bias = h.bias;
            return out;
        }
    }
    if (out.trace.hit) {
        const float h =
            primaryNormalSpacing(out.trace.t, v.options.pixelRadius, v.normalSpacingMin);
        const Vec3 n = estimateTapeNormal(v.field, seg.ray.at(out.trace.t), h, v.normals);
        out.normal = normalOrFacing(n, seg.ray.direction);
    }
    return out;
}

// The min/max buffer (Jamriška §6) of `plan`'s DDA grid for a camera, built on the host as the CPU
// renderer builds it; an empty buffer (its view: none) where the plan has no DDA grid or its
// settings turn the buffer off. Set PrimaryPixelView::minMax to its view.
MinMaxBuffer primaryMinMax(const RenderPlan& plan, const Camera& camera);
// Whether `plan`'s primary rays use a min/max buffer.
bool usesMinMax(const RenderPlan& plan);

// The view of `plan`'s field, camera and primary-ray options for one frame, without a min/max
// buffer (primaryMinMax). The plan must outlive it (the field's arrays are the plan's tape's).
// A plan with triangle primaries needs its meshes' view (MeshPrimaryTables::view of
// plan.meshPrimary->tables(), or their device copies).
PrimaryPixelView primaryPixelView(const RenderPlan& plan, const FrameView& frame,
                                  MeshPrimaryView meshes = {});

}  // namespace sdft
