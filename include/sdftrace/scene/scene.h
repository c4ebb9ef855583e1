// A parsed, validated scene: the field tree, materials, lights, camera and render settings.
#pragma once

#include <string>
#include <vector>

#include "sdftrace/field/node.h"
#include "sdftrace/render/camera.h"
#include "sdftrace/render/lighting.h"
#include "sdftrace/trace/trace_options.h"

namespace sdft {

enum class NormalEstimator { Central, Tetrahedral };

struct RenderSettings {
    TraceOptions trace;  // primary rays
    NormalEstimator normals = NormalEstimator::Tetrahedral;
    bool shadows = true;            // hard shadows by tracing to each light (Liktor 2008, §4.1)
    float maxDistance = 100.0f;     // t_max of primary rays (the scene bounds clip it further)
    float shadowOffsetMin = 1e-3f;  // eps_min of the shadow-ray origin offset
    bool boundsCulling = true;  // skip far union operands (docs/decisions/0002-bounds-culling.md)
    int threads = 0;            // 0 = all hardware threads
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
