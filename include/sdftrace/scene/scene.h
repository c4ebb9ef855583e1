// A parsed, validated scene: the field tree, materials, lights, camera and render settings.
#pragma once

#include <string>
#include <vector>

#include "sdftrace/field/node.h"
#include "sdftrace/render/camera.h"
#include "sdftrace/render/lighting.h"
#include "sdftrace/trace/grid_tracer.h"
#include "sdftrace/trace/trace_options.h"

namespace sdft {

enum class NormalEstimator { Central, Tetrahedral };

// How a scene that is a single grid (e.g. `sdftrace render field.sdfg`) is traced: Jamriška's
// two-level DDA (§4) or sphere tracing the trilinear field like any other object.
enum class GridTracerKind { Dda, SphereTrace };

struct RenderSettings {
    TraceOptions trace;  // primary rays
    NormalEstimator normals = NormalEstimator::Tetrahedral;
    bool shadows = true;            // hard shadows by tracing to each light (Liktor 2008, §4.1)
    float maxDistance = 100.0f;     // t_max of primary rays (the scene bounds clip it further)
    float shadowOffsetMin = 1e-3f;  // eps_min of the shadow-ray origin offset
    bool boundsCulling = true;  // skip far union operands (docs/decisions/0002-bounds-culling.md)
    int threads = 0;            // 0 = all hardware threads
    // Single-grid scenes (Jamriška 2010).
    GridTracerKind gridTracer = GridTracerKind::Dda;
    GridTraceOptions gridTrace;  // cell intersection (§4.2) and bit masks (§4.1)
    GridNormal gridNormals = GridNormal::InterpolationOfDifferences;  // §5 (his choice)
    int occluderThreshold = 0;   // §7 shadow rays: restart threshold n; 0 = plain traversal
    int minMaxResolution = 128;  // §6 min/max buffer pixels along the longer side; 0 = off
    int tileSize = 16;
};

struct Scene {
    NodePtr root;
    std::vector<Material> materials;
    Lighting lighting;
    CameraDesc camera;
    RenderSettings settings;
};

}  // namespace sdft
