#include "sdftrace/scene/plan_render.h"

namespace sdft {

RenderPlan planRender(const Scene& scene) {
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
