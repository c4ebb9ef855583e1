// A scene (the parsed description with its assets loaded) to the render plan the integrators
// consume (render/render_plan.h): the field compiled by the scene's settings, and the materials,
// textures, lights, camera and settings copied over.
#pragma once

#include "sdftrace/render/render_plan.h"
#include "sdftrace/scene/scene.h"

namespace sdft {

RenderPlan planRender(const Scene& scene);

}  // namespace sdft
