#include "sdftrace/render/render_plan.h"

#include <algorithm>

namespace sdft {

void compileField(RenderPlan& plan, const NodePtr& root) {
    const RenderSettings& s = plan.settings;
    plan.tape = compileTape(root, {.boundsCulling = s.boundsCulling, .pruning = s.pruning});
    plan.ddaGrid =
        root->kind == NodeKind::Grid && s.gridTracer == GridTracerKind::Dda ? root->grid : nullptr;
    plan.convexObjects.clear();
    // Keinert §3.5: each convex top-level object gets a tape of its own. Only rays inside a
    // dielectric look for their exit by them, so a scene without one (of thousands of objects,
    // say) compiles none.
    const bool refracts =
        std::any_of(plan.materials.begin(), plan.materials.end(),
                    [](const Material& m) { return m.kind == Material::Kind::Dielectric; });
    if (!s.convexBounds || !refracts) return;
    for (const NodePtr& o : topLevelObjects(root)) {
        const Bounds3 b = nodeBounds(*o);
        if (isConvex(*o) && b.finite() && !b.empty())
            plan.convexObjects.push_back({compileTape(o), b});
    }
}

float resolveMaxDistance(const RenderSettings& settings, const CameraDesc& camera,
                         const Bounds3& bounds) {
    if (!settings.maxDistanceAuto) return settings.maxDistance;
    const float base = RenderSettings{}.maxDistance;
    if (!bounds.finite() || bounds.empty()) return base;
    float corner = 0;
    for (int c = 0; c < 8; ++c) {
        const Vec3 p((c & 1) ? bounds.hi.x : bounds.lo.x, (c & 2) ? bounds.hi.y : bounds.lo.y,
                     (c & 4) ? bounds.hi.z : bounds.lo.z);
        corner = std::max(corner, length(p - camera.target));
    }
    // A little past the far corner: the last step of a ray grazing it.
    const float reach = 1.01f * (length(camera.eye - camera.target) + corner);
    return std::max(base, reach);
}

}  // namespace sdft
