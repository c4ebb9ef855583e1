#include "sdftrace/render/primary_pixel.h"

#include "sdftrace/render/render_plan.h"

namespace sdft {

std::string primaryPixelUnsupported(const RenderPlan& plan) {
    if (plan.ddaGrid) return "a single-grid scene traced by the two-level DDA";
    if (plan.meshPrimary) return "meshes whose primary rays hit their triangles";
    return {};
}

PrimaryPixelView primaryPixelView(const RenderPlan& plan, const FrameView& frame) {
    PrimaryPixelView v;
    v.field = plan.tape.view();
    v.camera = Camera(frame.camera);
    v.options = plan.settings.trace;
    v.options.pixelRadius = v.camera.pixelRadius();
    v.maxDistance = plan.settings.maxDistance;
    v.jitter[0] = frame.pixelJitter[0];
    v.jitter[1] = frame.pixelJitter[1];
    v.normals = plan.settings.normals;
    return v;
}

}  // namespace sdft
