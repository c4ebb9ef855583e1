// What the integrators consume (docs/design.md "one plan, two devices"): the scene's field compiled
// to a tape, the tapes of its convex top-level objects (Keinert et al. 2014, §3.5), the grid a
// single-grid scene is traced through by Jamriška's DDA, materials, textures, lights, the camera
// and the settings. Built once from a prepared scene (scene/plan_render.h) and read-only after;
// the renderers never look at the node tree. What changes per frame is a FrameView.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "sdftrace/field/device_resident_grid.h"
#include "sdftrace/field/grid.h"
#include "sdftrace/field/node.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/math/camera.h"
#include "sdftrace/render/horizon.h"
#include "sdftrace/render/lighting.h"
#include "sdftrace/render/mesh_primary.h"
#include "sdftrace/render/render_settings.h"
#include "sdftrace/render/texture.h"

namespace sdft {

// A convex top-level object's own field and bounding box (Keinert §3.5).
struct ConvexObject {
    Tape tape;
    Bounds3 bounds;
};

struct RenderPlan {
    Tape tape;                                // the whole field
    std::vector<ConvexObject> convexObjects;  // when settings.convexBounds
    std::shared_ptr<const Grid> ddaGrid;      // a single-grid scene traced by DDA; else null
    std::vector<Material> materials;
    std::vector<Texture> textures;     // referenced by materials
    std::vector<TextureImage> images;  // referenced by textures
    Lighting lighting;
    CameraDesc camera;
    RenderSettings settings;
    // settings.primaryTriangles: the meshes primary rays hit as triangles, and the field of
    // everything else (none when the scene is only meshes); shadows, AO and secondary rays use
    // `tape`.
    std::shared_ptr<const MeshPrimary> meshPrimary;
    std::optional<Tape> primaryField;
    // Grids of the tape whose current values are on the GPU: the GPU renderer binds them; the
    // CPU renderer refuses the plan (device_resident_grid.h).
    std::vector<DeviceResidentGrid> deviceGrids;
    // The field's bounds (nodeBounds of the scene's root; everything when unbounded), from which
    // settings.maxDistance is resolved for the plan's camera (resolveMaxDistance).
    Bounds3 sceneBounds = Bounds3::everything();
    // The top-level infinite planes, seen to the horizon (horizon.h); with them the automatic
    // t_max reaches past the rest of the scene, not the planes.
    HorizonPlanes horizon;
};

// Primary rays' t_max for `camera`: settings.maxDistance as given, or while it is automatic
// (RenderSettings::maxDistanceAuto) the default raised to reach past every corner of `bounds`
// from any eye at the camera's distance from its target (|eye - target| + the farthest corner's
// distance from the target: the same for every orbit about the target). Unbounded scenes keep
// the default.
float resolveMaxDistance(const RenderSettings& settings, const CameraDesc& camera,
                         const Bounds3& bounds);

// What changes between frames of one plan (temporal.h): the camera, the frame number that seeds
// per-pixel random sequences, and the subpixel offset of primary rays.
struct FrameView {
    CameraDesc camera;
    uint32_t frame = 0;
    float pixelJitter[2] = {0, 0};  // primary rays through (x + 0.5 + jx, y + 0.5 + jy)
};

// Compiles the field part of `plan` from the scene's root node by `plan.settings`: the tape (with
// bounds culling when enabled), the DDA grid and, when `plan.materials` has a dielectric, the
// convex objects.
void compileField(RenderPlan& plan, const NodePtr& root);

}  // namespace sdft
