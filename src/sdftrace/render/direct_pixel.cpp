#include "sdftrace/render/direct_pixel.h"

#include <algorithm>
#include <cmath>

#include "sdftrace/render/path_pixel.h"
#include "sdftrace/render/render_plan.h"
#include "sdftrace/render/whitted_pixel.h"

namespace sdft {

std::string directPixelUnsupported(const RenderPlan& plan) {
    const RenderSettings& s = plan.settings;
    if (s.shadows && (s.shadowMethod == ShadowMethod::Pcf || s.shadowMethod == ShadowMethod::Evsm))
        return "shadow maps (pcf, evsm)";
    if (!s.pathTracing && planHasWhitted(plan) &&
        s.maxReflections + s.maxRefractions > kWhittedMaxBounces)
        return "Whitted budgets above " + std::to_string(kWhittedMaxBounces) +
               " bounces in all (max_reflections + max_refractions)";
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
    for (const Material& m : plan.materials) t.materials.push_back(pixelMaterial(m));
    for (const Texture& x : plan.textures) t.textures.push_back(x);
    for (const TextureImage& image : plan.images) t.images.push_back(image.view());
    if (plan.meshPrimary) {
        t.meshes = plan.meshPrimary->tables();
        // Meshes posed on the GPU have no host arrays: the GPU renderer makes its own view.
        bool host = true;
        for (const MeshPrimaryTables::Mesh& m : t.meshes.meshes) host = host && !m.device;
        if (host) t.meshView = t.meshes.view();
    }
    return t;
}

DirectPixelView directPixelView(const RenderPlan& plan, const FrameView& frame,
                                const DirectPixelTables& tables, int filmWidth) {
    const RenderSettings& s = plan.settings;
    DirectPixelView v;
    v.primary = primaryPixelView(plan, frame, tables.meshView);
    v.lights = tables.lights.data();
    v.lightCount = static_cast<int>(tables.lights.size());
    v.materials = tables.materials.data();
    v.materialCount = static_cast<int>(tables.materials.size());
    v.textures = tables.textures.data();
    v.textureCount = static_cast<int>(tables.textures.size());
    v.images = {tables.images.data(), static_cast<int>(tables.images.size())};
    const int only = plan.tape.uniformMaterial();
    v.uniformMaterial =
        only >= 0 && only < v.materialCount && tables.materials[only].colorTexture < 0 ? only : -1;
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

PathPixelView pathPixelView(const RenderPlan& plan, const FrameView& frame,
                            const DirectPixelTables& tables) {
    const RenderSettings& s = plan.settings;
    PathPixelView v;
    v.direct = directPixelView(plan, frame, tables, frame.camera.width);
    v.secondary = s.trace.secondary();
    v.occlusion = s.trace.occlusion();
    v.offsetMin = s.shadowOffsetMin;
    v.environment = plan.lighting.environment;
    v.maxDepth = s.maxDepth;
    v.samplesPerPixel = std::max(1, s.samplesPerPixel);
    v.seedWidth = frame.camera.width;
    return v;
}

WhittedPixelTables whittedPixelTables(const RenderPlan& plan) {
    WhittedPixelTables t;
    for (const ConvexObject& c : plan.convexObjects) t.convex.push_back({c.tape.view(), c.bounds});
    return t;
}

WhittedPixelView whittedPixelView(const RenderPlan& plan, const WhittedPixelTables& tables) {
    const RenderSettings& s = plan.settings;
    WhittedPixelView w;
    w.convex = tables.convex.data();
    w.convexCount = static_cast<int>(tables.convex.size());
    w.maxReflections = s.maxReflections;
    w.maxRefractions = s.maxRefractions;
    w.dynamicEpsilon = s.dynamicEpsilon;
    w.globalEpsilon = s.globalEpsilon;
    w.offsetMin = s.shadowOffsetMin;
    w.secondary = s.trace.secondary();
    w.shadows = secondaryShadows(s);
    return w;
}

SecondaryShadows secondaryShadows(const RenderSettings& s) {
    SecondaryShadows o;
    o.enabled = s.shadows;
    o.method = s.shadowMethod;
    o.rays = std::max(1, s.shadowRays);
    o.offsetMin = s.shadowOffsetMin;
    o.maxDistance = s.maxDistance;
    o.ray = s.trace.occlusion();
    o.soft = s.soft;
    o.soft.epsilon = std::fmax(o.soft.epsilon, s.trace.tau);
    o.soft.jitter = false;
    return o;
}

bool planHasWhitted(const RenderPlan& plan) {
    for (const Material& m : plan.materials)
        if (m.kind != Material::Kind::Plastic) return true;
    return false;
}

}  // namespace sdft
