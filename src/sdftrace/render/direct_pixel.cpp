#include "sdftrace/render/direct_pixel.h"

#include "sdftrace/render/render_plan.h"

namespace sdft {

std::string directPixelUnsupported(const RenderPlan& plan) {
    std::string why = primaryPixelUnsupported(plan);
    if (!why.empty()) return why;
    const RenderSettings& s = plan.settings;
    if (s.pathTracing) return "the path tracer";
    if (s.shadows && (s.shadowMethod == ShadowMethod::Pcf || s.shadowMethod == ShadowMethod::Evsm))
        return "shadow maps (pcf, evsm)";
    for (const Material& m : plan.materials) {
        if (m.kind != Material::Kind::Plastic)
            return "material '" + m.name + "': mirrors and dielectrics (Whitted rays)";
        if (m.colorTexture >= 0) return "material '" + m.name + "': textures";
    }
    if (plan.materials.empty()) return "a plan without materials";
    return {};
}

float shadowOffsetMin(const RenderPlan& plan) {
    const float eps = plan.settings.shadowOffsetMin;
    return plan.ddaGrid ? std::fmax(eps, 0.5f * plan.ddaGrid->shape().voxelSize) : eps;
}

SoftShadowOptions softShadowOptions(const RenderPlan& plan) {
    const RenderSettings& s = plan.settings;
    SoftShadowOptions o = s.soft;
    o.epsilon = plan.ddaGrid ? shadowOffsetMin(plan) : std::fmax(o.epsilon, s.trace.tau);
    o.maxSteps = std::max(o.maxSteps, s.trace.maxSteps);
    return o;
}

DirectPixelTables directPixelTables(const RenderPlan& plan) {
    DirectPixelTables t;
    t.lights = plan.lighting.lights;
    t.materials.reserve(plan.materials.size());
    for (const Material& m : plan.materials)
        t.materials.push_back({m.color, m.diffuse, m.specular, m.shininess});
    return t;
}

DirectPixelView directPixelView(const RenderPlan& plan, const FrameView& frame,
                                const DirectPixelTables& tables, int filmWidth) {
    const RenderSettings& s = plan.settings;
    DirectPixelView v;
    v.primary = primaryPixelView(plan, frame);
    v.lights = tables.lights.data();
    v.lightCount = static_cast<int>(tables.lights.size());
    v.materials = tables.materials.data();
    v.materialCount = static_cast<int>(tables.materials.size());
    const int only = plan.tape.uniformMaterial();
    v.uniformMaterial = only < v.materialCount ? only : -1;
    v.ambient = plan.lighting.ambient;
    v.background = plan.lighting.background;
    v.shadows = s.shadows;
    v.shadowMethod = s.shadowMethod;
    v.shadowRay = s.trace.occlusion();
    // The renderer's soft-shadow march (renderer.cpp): no closer than the primary rays' tau, and
    // at least their step budget.
    v.shadowOffsetMin = shadowOffsetMin(plan);
    v.occluderThreshold = s.occluderThreshold;
    v.soft = softShadowOptions(plan);
    v.shadowRays = s.shadowRays;
    v.ambientOcclusion = s.ambientOcclusion;
    v.ao = s.ao;
    v.filmWidth = filmWidth;
    v.frame = frame.frame;
    return v;
}

}  // namespace sdft
