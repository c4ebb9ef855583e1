#include "sdftrace/scene/plan_render.h"

#include <algorithm>

#include "placed_meshes.h"
#include "sdftrace/core/macros.h"
#include "sdftrace/field/grid.h"
#include "sdftrace/scene/render_options.h"

namespace sdft {

namespace {

// World size of one voxel of a mesh's grid under its placement.
float worldVoxel(const Placement& placement, const Grid& grid) {
    const float v = grid.shape().voxelSize;
    const Vec3 o = placement.toWorld(Vec3(0.0f));
    float size = 0;
    for (const Vec3 axis : {Vec3(v, 0, 0), Vec3(0, v, 0), Vec3(0, 0, v)})
        size = std::max(size, length(placement.toWorld(axis) - o));
    return size;
}

// RTSDF's hybrid mode: the mesh grids reached from the root through unions and transforms move
// to `out` as triangles under their placement; what remains is
// returned (null when nothing does). Meshes under other operators stay in the field.
NodePtr takeMeshes(const NodePtr& n, const Scene& scene, Placement placement,
                   std::vector<PlacedMesh>& out) {
    if (n->kind == NodeKind::Grid) {
        auto it = scene.meshes.find(n->grid.get());
        if (it == scene.meshes.end()) return n;
        PlacedMesh m;
        m.mesh = it->second;
        m.device = deviceStateOf(scene.deviceGrids, n->grid.get());
        if (!m.device) {
            const auto accel = scene.meshAccels.find(m.mesh.get());
            m.accel = accel != scene.meshAccels.end() ? accel->second
                                                      : std::make_shared<const MeshAccel>(m.mesh);
        }
        m.placement = placement;
        m.bias = worldVoxel(placement, *n->grid);
        out.push_back(std::move(m));
        return nullptr;
    }
    if (n->kind == NodeKind::Union) {
        std::vector<NodePtr> kept;
        for (const NodePtr& c : n->children)
            if (NodePtr k = takeMeshes(c, scene, placement, out)) kept.push_back(k);
        if (kept.empty()) return nullptr;
        if (kept.size() == n->children.size()) return n;
        auto copy = std::make_shared<Node>(*n);
        copy->children = std::move(kept);
        return copy;
    }
    if (isPlacementKind(n->kind)) {
        placement.append(*n);
        NodePtr child = takeMeshes(n->children[0], scene, placement, out);
        if (!child) return nullptr;
        if (child == n->children[0]) return n;
        auto copy = std::make_shared<Node>(*n);
        copy->children = {child};
        return copy;
    }
    return n;
}

}  // namespace

RenderPlan planRender(const Scene& scene) {
    SDFT_CHECK(scene.prepared());  // prepareScene first: grids are still pending
    RenderPlan plan;
    plan.materials = scene.materials;
    plan.textures = scene.textures;
    plan.images = scene.images;
    plan.lighting = scene.lighting;
    plan.camera = scene.camera;
    plan.settings = scene.settings;
    plan.deviceGrids = scene.deviceGrids;
    compileField(plan, scene.root);
    plan.sceneBounds = nodeBounds(*scene.root);
    plan.horizon = horizonPlanes(scene.root);
    scaleLengthDefaults(plan.settings, sceneLengthFactor(plan.sceneBounds, plan.camera));
    plan.settings.maxDistance = resolveMaxDistance(
        plan.settings, plan.camera, plan.horizon.count ? plan.horizon.rest : plan.sceneBounds);
    if (plan.settings.primaryTriangles && !scene.meshes.empty()) {
        std::vector<PlacedMesh> meshes;
        const NodePtr rest = takeMeshes(scene.root, scene, {}, meshes);
        if (!meshes.empty()) {
            plan.meshPrimary = std::make_shared<const PlacedMeshes>(std::move(meshes));
            if (rest)
                plan.primaryField = compileTape(rest, {.boundsCulling = plan.settings.boundsCulling,
                                                       .pruning = plan.settings.pruning});
            plan.ddaGrid = nullptr;  // a mesh's primary rays are Embree's; shadows sphere trace
        }
    }
    return plan;
}

}  // namespace sdft
