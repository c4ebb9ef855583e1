#include "sdftrace/render/render_plan.h"

namespace sdft {

void compileField(RenderPlan& plan, const NodePtr& root) {
    const RenderSettings& s = plan.settings;
    plan.tape = compileTape(root, {.boundsCulling = s.boundsCulling});
    plan.ddaGrid =
        root->kind == NodeKind::Grid && s.gridTracer == GridTracerKind::Dda ? root->grid : nullptr;
    plan.convexObjects.clear();
    if (!s.convexBounds) return;
    // Keinert §3.5: each convex top-level object gets a tape of its own.
    std::vector<NodePtr> objects;
    if (root->kind == NodeKind::Union)
        objects = root->children;
    else
        objects.push_back(root);
    for (const NodePtr& o : objects) {
        const Bounds3 b = nodeBounds(*o);
        if (isConvex(*o) && b.finite() && !b.empty())
            plan.convexObjects.push_back({compileTape(o), b});
    }
}

}  // namespace sdft
