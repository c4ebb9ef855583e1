#include "sdftrace/scene/plan_render.h"

#include "sdftrace/core/macros.h"

namespace sdft {

RenderPlan planRender(const Scene& scene) {
    SDFT_CHECK(scene.prepared());  // prepareScene first: grids are still pending
    RenderPlan plan;
    plan.materials = scene.materials;
    plan.textures = scene.textures;
    plan.images = scene.images;
    plan.lighting = scene.lighting;
    plan.camera = scene.camera;
    plan.settings = scene.settings;
    compileField(plan, scene.root);
    return plan;
}

}  // namespace sdft
