// Render settings: every switch of the tracers and integrators, with the defaults users get. The
// scene file's "render" block and the CLI's flags set them through one option table
// (scene/render_options.h).
#pragma once

#include <cstdint>

#include "sdftrace/render/ambient_occlusion.h"
#include "sdftrace/render/shadow_map.h"
#include "sdftrace/render/soft_shadow.h"
#include "sdftrace/trace/grid_tracer.h"
#include "sdftrace/trace/trace_options.h"

namespace sdft {

enum class NormalEstimator { Central, Tetrahedral };

// How a scene that is a single grid (e.g. `sdftrace render field.sdfg`) is traced: Jamriška's
// two-level DDA (§4) or sphere tracing the trilinear field like any other object.
enum class GridTracerKind { Dda, SphereTrace };

// How shadows of the lights are found (RTSDF §3 compares the last four).
enum class ShadowMethod {
    Hard,         // one ray to the light's centre (Liktor 2008, §4.1)
    Soft,         // SDF soft shadows: one march (soft_shadow.h, RTSDF §2.4-2.5)
    Distributed,  // ground truth: rays to points sampled on the light (Cook et al. 1984)
    Pcf,          // shadow map, percentage-closer filtered (shadow_map.h)
    Evsm,         // shadow map, exponential variance (shadow_map.h)
};

struct RenderSettings {
    TraceOptions trace;  // primary rays
    NormalEstimator normals = NormalEstimator::Tetrahedral;
    bool shadows = true;  // lights with `castShadows` cast them, by `shadowMethod`
    ShadowMethod shadowMethod = ShadowMethod::Hard;
    SoftShadowOptions soft;
    int shadowRays = 64;  // Distributed: stratified samples of the light per point
    ShadowMapOptions shadowMap;
    bool ambientOcclusion = false;  // scales the ambient term (ambient_occlusion.h)
    AmbientOcclusionOptions ao;
    // Whitted reflection and refraction (Keinert §4): bounce budgets per kind, and the secondary
    // ray's origin offset: Keinert §3.3's dynamic 2 max(eps_min, |f(p)|) (eps_min is
    // shadowOffsetMin), or a global epsilon along the normal.
    int maxReflections = 2, maxRefractions = 8;
    bool dynamicEpsilon = true;
    float globalEpsilon = 1e-3f;
    bool convexBounds = true;  // Keinert §3.5 for rays inside convex objects
    // RTSDF's hybrid mode: primary rays hit the triangles of mesh objects (mesh_primary.h),
    // shadows and AO march their SDFs.
    bool primaryTriangles = false;
    // The integrator: direct lighting (the tile renderer) or the path tracer (path_tracer.h).
    bool pathTracing = false;
    int samplesPerPixel = 16;  // path tracer
    int maxDepth = 5;          // path tracer: scattering events per path
    // t_max of primary rays (the scene bounds clip it further). While `maxDistanceAuto`
    // (max_distance not given, or 0), planRender raises it to reach past the scene's bounds from
    // any camera at the camera's distance from its target (resolveMaxDistance, render_plan.h).
    float maxDistance = 100.0f;
    bool maxDistanceAuto = true;
    // The smallest spacing of the normals' finite differences (scene units; scaled down with a
    // scene smaller than a unit, scaleLengthDefaults).
    float normalSpacingMin = 1e-4f;
    // The options the user gave (bit i: renderOptions()[i], RenderOption::give).
    uint64_t given = 0;
    float shadowOffsetMin = 1e-3f;  // eps_min of the shadow-ray origin offset
    bool boundsCulling = true;  // skip far union operands (docs/decisions/0002-bounds-culling.md)
    bool pruning = true;        // per-cell pruned tapes (docs/decisions/0021-lipschitz-pruning.md)
    int threads = 0;            // 0 = all hardware threads
    // Single-grid scenes (Jamriška 2010).
    GridTracerKind gridTracer = GridTracerKind::Dda;
    GridTraceOptions gridTrace;  // cell intersection (§4.2) and bit masks (§4.1)
    GridNormal gridNormals = GridNormal::InterpolationOfDifferences;  // §5 (his choice)
    int occluderThreshold = 0;   // §7 shadow rays: restart threshold n; 0 = plain traversal
    int minMaxResolution = 128;  // §6 min/max buffer pixels along the longer side; 0 = off
    int tileSize = 16;
};

}  // namespace sdft
