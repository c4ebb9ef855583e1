// The direct-lighting integrator, the one both devices run: a hit's material blend, ambient
// occlusion, and each light's Lambert + Blinn-Phong term where its shadow method lets it through.
// The pieces (materialAt, ambientLight, shadowRays, softShadowRay, lightTerm) are shared: a device
// thread runs them for its pixel in order (shadeDirectPixel, each shadow ray traced as it comes);
// the CPU renderer runs them for a tile's hits, tracing the tile's shadow rays and marches of a
// light together as packets (renderer.cpp). direct_pixel_test.cpp holds the two orders to each
// other on the examples. The shadow methods: hard rays with Keinert et al. 2014 §3.3's dynamic
// origin offset, RTSDF's SDF soft shadows (§2.4-2.5, soft_shadow.h) and distributed rays to
// points sampled on the light (Cook et al. 1984), seeded per pixel and frame.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "sdftrace/core/macros.h"
#include "sdftrace/math/sampling.h"
#include "sdftrace/render/ambient_occlusion.h"
#include "sdftrace/render/light_sample.h"
#include "sdftrace/render/lighting.h"
#include "sdftrace/render/primary_pixel.h"
#include "sdftrace/render/render_settings.h"
#include "sdftrace/render/soft_shadow.h"
#include "sdftrace/render/texture.h"

namespace sdft {

// A material as the per-pixel path shades it: Material (lighting.h) without its name. Mirrors
// and dielectrics are shaded by Whitted rays (whitted_pixel.h).
struct PixelMaterial {
    Vec3 color{0.8f, 0.8f, 0.8f};
    float diffuse = 1, specular = 0.2f, shininess = 32;
    Material::Kind kind = Material::Kind::Plastic;
    float ior = 1.5f;
    Vec3 absorption{0, 0, 0};
    float roughness = -1;   // the path tracer's GGX alpha; < 0: from the shininess
    int colorTexture = -1;  // >= 0: the colour is this texture's (DirectPixelView::textures)
};

// A material without its name.
inline PixelMaterial pixelMaterial(const Material& m) {
    return {m.color, m.diffuse,    m.specular,  m.shininess,   m.kind,
            m.ior,   m.absorption, m.roughness, m.colorTexture};
}

// Plain data: a kernel takes it by value. The light and material arrays are the caller's
// (DirectPixelTables on the CPU, device copies on a GPU).
struct DirectPixelView {
    PrimaryPixelView primary;
    const Light* lights = nullptr;
    int lightCount = 0;
    const PixelMaterial* materials = nullptr;
    int materialCount = 0;
    int uniformMaterial = -1;  // >= 0: every point's material (Tape::uniformMaterial, untextured)
    const TextureParams* textures = nullptr;  // the materials' colour textures
    int textureCount = 0;
    ImageTable images;  // the textures' images
    Vec3 ambient{0, 0, 0}, background{0, 0, 0};
    bool shadows = true;
    ShadowMethod shadowMethod = ShadowMethod::Hard;
    TraceOptions shadowRay;  // hard and distributed rays: hit or miss only
    SoftShadowOptions soft;  // with the renderer's epsilon and step budget
    int shadowRays = 64;
    float shadowOffsetMin = 1e-3f;  // eps_min (a DDA grid's: at least half a voxel)
    int occluderThreshold = 0;      // DDA shadow rays: Jamriška §7's restart threshold
    bool ambientOcclusion = false;
    AmbientOcclusionOptions ao;
    int filmWidth = 0;   // pixel (x, y) seeds its random numbers with y * filmWidth + x
    uint32_t frame = 0;  // FrameView::frame
};

struct DirectPixel {
    PrimaryPixel primary;    // its DDA counters include the shadow rays'
    PixelMaterial material;  // at the hit

    Vec3 color{0, 0, 0};  // finite: the background on a miss, 0 where shading overflowed
    float shadow = 1;     // the first shadow-casting light's visibility
    float ao = 1;
    uint32_t shadowEvaluations = 0, aoEvaluations = 0;
    // Whitted rays from a mirror or dielectric hit (whitted_pixel.h): rays, their evaluations
    // (secondary hits' shadow rays included) and self-intersections.
    uint32_t secondaryRays = 0, secondaryEvaluations = 0, selfIntersections = 0;
};

// A weighted sum of materials (a material blend, Keinert et al. 2014 §4): every parameter summed
// by weight, the roughness over the materials that set one, the kind the heaviest weight's. The
// CPU's materialAt and the per-pixel lookup below both sum with it (colours already textured; the
// sum has no texture).
class MaterialMix {
  public:
    SDFT_HOST_DEVICE MaterialMix() {
        m_sum.color = Vec3(0.0f);
        m_sum.diffuse = m_sum.specular = m_sum.shininess = 0;
        m_sum.ior = 0;
        m_sum.absorption = Vec3(0.0f);
        m_sum.roughness = 0;
    }
    // `src` with weight w (its colour the textured one where it has a texture).
    SDFT_HOST_DEVICE void add(const PixelMaterial& src, float w) {
        m_sum.color += src.color * w;
        m_sum.diffuse += src.diffuse * w;
        m_sum.specular += src.specular * w;
        m_sum.shininess += src.shininess * w;
        m_sum.ior += src.ior * w;
        m_sum.absorption += src.absorption * w;
        if (src.roughness >= 0) {
            m_sum.roughness += src.roughness * w;
            m_roughWeight += w;
        }
        if (w > m_heaviest) {
            m_heaviest = w;
            m_sum.kind = src.kind;
        }
    }
    SDFT_HOST_DEVICE PixelMaterial result() const {
        PixelMaterial m = m_sum;
        m.roughness = m_roughWeight > 0 ? m_sum.roughness / m_roughWeight : -1;
        return m;
    }

  private:
    PixelMaterial m_sum;
    float m_heaviest = -1, m_roughWeight = 0;
};

namespace direct_pixel {

// The material table's entry of a blend's id (clamped: a tape's ids index the plan's table).
SDFT_HOST_DEVICE inline int materialIndex(const DirectPixelView& v, int id) {
    return id < 0 ? 0 : id > v.materialCount - 1 ? v.materialCount - 1 : id;
}

// Whether a texture of a material in blend b reads the surface normal.
SDFT_HOST_DEVICE inline bool textureNeedsNormal(const DirectPixelView& v, const MaterialBlend& b) {
    for (int i = 0; i < b.count; ++i) {
        const int t = v.materials[materialIndex(v, b.id[i])].colorTexture;
        if (t >= 0 && t < v.textureCount && textureNeedsNormal(v.textures[t])) return true;
    }
    return false;
}

// The blend of the materials at the surface point p (n its unit world normal), colour textures
// looked up in each material's object frame (texture.h) as the CPU's materialAt does.
template <int kMaterialRegs>
SDFT_HOST_DEVICE inline PixelMaterial materialAt(const DirectPixelView& v, Vec3 p, Vec3 n) {
    if (v.uniformMaterial >= 0 && v.uniformMaterial < v.materialCount)
        return v.materials[v.uniformMaterial];
    // The blend at p and, where a texture needs the normal, a step along n (one call site: one
    // register file on a device's stack).
    MaterialBlend blends[2];
    for (int pass = 0; pass < 2; ++pass) {
        evalTapeAt<kMaterialRegs>(v.primary.field, pass ? p + n * textureNormalStep(p) : p,
                                  &blends[pass]);
        if (pass == 0 && !textureNeedsNormal(v, blends[0])) break;
    }
    const MaterialBlend& b = blends[0];
    MaterialMix mix;
    for (int i = 0; i < b.count; ++i) {
        PixelMaterial src = v.materials[materialIndex(v, b.id[i])];
        if (src.colorTexture >= 0 && src.colorTexture < v.textureCount) {
            const TextureParams& t = v.textures[src.colorTexture];
            src.color = evalTexture(
                t, v.images, textureInputs(b, i, textureNeedsNormal(t) ? &blends[1] : nullptr));
        }
        mix.add(src, b.weight[i]);
    }
    return mix.result();
}

// Counters of one pixel's shadow rays.
struct ShadowCounters {
    uint32_t evaluations = 0;
    int traversalSteps = 0, intersectionTests = 0;  // DDA
};

// A ray to the light: blocked or not (a lone grid's by its DDA, Jamriška §7).
SDFT_HOST_DEVICE inline bool occluded(const DirectPixelView& v, Vec3 origin, Vec3 dir, float tMax,
                                      ShadowCounters& c) {
    if (v.primary.ddaGrid >= 0) {
        const GridTraceResult r =
            grid_dda::traceShadow(v.primary.field.grids[v.primary.ddaGrid], {origin, dir}, 0.0f,
                                  tMax, v.primary.gridTrace, v.occluderThreshold);
        c.evaluations += static_cast<uint32_t>(r.interpolations);
        c.traversalSteps += r.traversalSteps;
        c.intersectionTests += r.intersectionTests;
        return r.hit;
    }
    const TraceResult r = traceTapeRay(v.primary.field, {{origin, dir}, 0.0f, tMax}, v.shadowRay);
    c.evaluations += static_cast<uint32_t>(r.evaluations);
    return r.hit;
}

// Keinert et al. 2014, §3.3: shadow rays start 2 max(eps_min, |f(p)| / L) off the surface (along
// its normal), so they clear it however far from it the march stopped. A DDA hit has f = 0 by
// construction: its eps_min is at least half a voxel (shadowOffsetMin).
SDFT_HOST_DEVICE inline float shadowOffset(const DirectPixelView& v, float value) {
    return 2.0f * std::fmax(v.shadowOffsetMin, std::fabs(value) / v.primary.field.lipschitz);
}

// Pixel (x, y)'s index, which seeds its random numbers.
SDFT_HOST_DEVICE inline uint32_t pixelSeed(const DirectPixelView& v, int x, int y) {
    return static_cast<uint32_t>(y) * static_cast<uint32_t>(v.filmWidth) + static_cast<uint32_t>(x);
}

// The ambient light leaving the hit p (unit normal n) of material m: the ambient colour times the
// material's, scaled by ambient occlusion where it is on (`ao` its factor, its evaluations added).
SDFT_HOST_DEVICE inline Vec3 ambientLight(const DirectPixelView& v, Vec3 p, Vec3 n,
                                          const PixelMaterial& m, float& ao,
                                          uint32_t& evaluations) {
    Vec3 radiance = v.ambient * m.color;
    ao = 1;
    if (v.ambientOcclusion) {
        const AmbientOcclusionResult r = ambientOcclusionTape(v.primary.field, p, n, v.ao);
        ao = r.ao;
        radiance *= r.ao;
        evaluations += static_cast<uint32_t>(r.evaluations);
    }
    return radiance;
}

// Light `light`'s Lambert + Blinn-Phong term at p (unit normal n) seen along d, the share
// `visible` of it unblocked; nothing where the light is below the horizon.
SDFT_HOST_DEVICE inline Vec3 lightTerm(const Light& light, const PixelMaterial& m, Vec3 p, Vec3 n,
                                       Vec3 d, float visible) {
    if (visible == 0) return Vec3(0.0f);
    const LightDirection to = towardLight(light, p);
    if (dot(n, to.dir) <= 0) return Vec3(0.0f);
    return blinnPhong(m.color, m.diffuse, m.specular, m.shininess, n, to.dir, d) * light.color *
           (to.scale * visible);
}

// Whether light `light` is seen by shadow rays (hard, or distributed; a point light's distributed
// rays are one hard ray), rather than by a soft-shadow march or a shadow map.
SDFT_HOST_DEVICE inline bool seenByShadowRays(const DirectPixelView& v, const Light& light) {
    return v.shadowMethod == ShadowMethod::Hard ||
           (v.shadowMethod == ShadowMethod::Distributed && !light.hasSize());
}

// The shadow rays by which the hit p (unit normal n) sees light `li`: hard, one ray to the
// light's centre; distributed (Cook et al. 1984), v.shadowRays rays to points on the light along
// a per-pixel rotated Halton sequence continued from frame to frame, so accumulated frames
// converge as one frame with all their rays would. Each ray above the surface's tangent plane is
// handed to emit(origin, dir, tMax); the visibility is the share of `rays` that reach the light:
// `seen` (points inside the light, seen without a ray) plus the emitted rays that are not
// blocked. A device traces each ray as it comes; the CPU renderer gathers a tile's into packets.
struct ShadowRayShare {
    int rays = 1, seen = 0;
};
template <class Emit>
SDFT_HOST_DEVICE inline ShadowRayShare shadowRays(const DirectPixelView& v, const Light& light,
                                                  int li, Vec3 p, Vec3 n, float offset,
                                                  uint32_t pixel, Emit&& emit) {
    const Vec3 origin = p + n * offset;
    ShadowRayShare share;
    if (seenByShadowRays(v, light)) {
        const LightDirection to = towardLight(light, p);
        if (dot(n, to.dir) > 0) emit(origin, to.dir, to.dist);  // else below the horizon
        return share;
    }
    share.rays = v.shadowRays > 1 ? v.shadowRays : 1;
    Rng rng(pixel, 0xD157u + static_cast<uint32_t>(li));
    const float r1 = rng.uniform(), r2 = rng.uniform();
    for (int k = 0; k < share.rays; ++k) {
        float u1, u2;
        rotatedHalton(v.frame * static_cast<uint32_t>(share.rays) + static_cast<uint32_t>(k), r1,
                      r2, u1, u2);
        const LightSample ls = sampleLight(light, p, u1, u2);
        if (ls.dist <= 0) {  // inside the light
            ++share.seen;
        } else if (dot(n, ls.dir) > 0) {
            emit(origin, ls.dir, ls.dist);
        }
    }
    return share;
}

// RTSDF §2.4-2.5: the soft-shadow march from the hit p (unit normal n) towards light `li`'s
// centre, its start jittered per pixel and frame; false where the light is below the horizon
// (visibility 0).
SDFT_HOST_DEVICE inline bool softShadowRay(const DirectPixelView& v, const Light& light, int li,
                                           Vec3 p, Vec3 n, float offset, uint32_t pixel,
                                           SoftShadowRay& ray) {
    const LightDirection to = towardLight(light, p);
    if (dot(n, to.dir) <= 0) return false;
    Rng rng(pixel, v.frame, 0x50F7u + static_cast<uint32_t>(li));
    ray.origin = p + n * offset;
    ray.dir = to.dir;
    ray.tMin = 0;
    ray.tMax = std::fmin(to.dist, v.primary.maxDistance);
    ray.tanRadius = lightTanRadius(light, p);
    ray.jitter01 = rng.uniform();
    return true;
}

// How much of light `li` the hit at p (unit normal n) sees, in [0, 1], each ray traced as it
// comes (a device thread's order; the CPU renderer traces a tile's rays together).
SDFT_HOST_DEVICE inline float visibility(const DirectPixelView& v, const Light& light, int li,
                                         Vec3 p, Vec3 n, float offset, uint32_t pixel,
                                         ShadowCounters& counters) {
    if (v.shadowMethod == ShadowMethod::Soft) {
        SoftShadowRay r;
        if (!softShadowRay(v, light, li, p, n, offset, pixel, r)) return 0.0f;
        const SoftShadowResult s = softShadowTape(v.primary.field, r.origin, r.dir, r.tMin, r.tMax,
                                                  r.tanRadius, v.soft, r.jitter01);
        counters.evaluations += static_cast<uint32_t>(s.evaluations);
        return s.visibility;
    }
    int seen = 0;
    const ShadowRayShare share =
        shadowRays(v, light, li, p, n, offset, pixel, [&](Vec3 origin, Vec3 dir, float tMax) {
            seen += !occluded(v, origin, dir, tMax, counters);
        });
    return static_cast<float>(share.seen + seen) / static_cast<float>(share.rays);
}

}  // namespace direct_pixel

// Pixel (x, y), shaded. kMaterialRegs: the material register file (at least the tape's scalar
// registers unless the view has a uniform material; a device picks the smallest that fits).
template <int kMaterialRegs>
SDFT_HOST_DEVICE inline DirectPixel shadeDirectPixel(const DirectPixelView& v, int x, int y) {
    using namespace direct_pixel;
    DirectPixel out;
    out.primary = tracePrimaryPixel(v.primary, x, y);
    out.color = v.background;
    if (!out.primary.trace.hit) return out;
    const Ray ray = primaryRay(v.primary.camera, x, y, v.primary.jitter);
    const Vec3 n = out.primary.normal;
    // On a triangle (hybrid mode) the shading point lies a voxel of the mesh's grid off it
    // (RTSDF §2.5.3), as the renderer's placeTriangleHits puts it.
    const Vec3 p = ray.at(out.primary.trace.t) + n * out.primary.bias;
    const PixelMaterial m = materialAt<kMaterialRegs>(v, p, n);
    out.material = m;
    Vec3 radiance = ambientLight(v, p, n, m, out.ao, out.aoEvaluations);
    const float offset = shadowOffset(v, out.primary.trace.value);
    const uint32_t pixel = pixelSeed(v, x, y);
    bool firstShadow = true;
    ShadowCounters counters;
    for (int li = 0; li < v.lightCount; ++li) {
        const Light& light = v.lights[li];
        float visible = 1;
        if (v.shadows && light.castShadows) {
            visible = visibility(v, light, li, p, n, offset, pixel, counters);
            if (firstShadow) out.shadow = visible;
            firstShadow = false;
        }
        radiance += lightTerm(light, m, p, n, ray.direction, visible);
    }
    out.color = isFinite(radiance) ? radiance : Vec3(0.0f);
    out.shadowEvaluations = counters.evaluations;
    out.primary.traversalSteps += counters.traversalSteps;
    out.primary.intersectionTests += counters.intersectionTests;
    return out;
}

// Why `plan` cannot be shaded per pixel (empty when it can; mirrors and dielectrics by
// shadePixel, whitted_pixel.h, the path tracer by pathRadiance, path_pixel.h, triangle primaries
// by tracePrimaryPixel): shadow maps and Whitted budgets deeper than its stack stay on the CPU
// renderer for now.
std::string directPixelUnsupported(const RenderPlan& plan);

// The shadow rays' eps_min of `plan` (Keinert et al. 2014, §3.3): the settings', and at least
// half a voxel for a lone grid traced by the DDA, whose trilinear field can stay <= 0 for a
// fraction of a voxel along the gradient near creases. Shared by the CPU renderer.
float shadowOffsetMin(const RenderPlan& plan);
// The soft-shadow march of `plan`'s shadow rays (RTSDF §2.4-2.5): the settings' with an epsilon
// no finer than the primary rays' tau (eps_min for a DDA grid) and at least their step budget.
// Shared by the CPU renderer.
SoftShadowOptions softShadowOptions(const RenderPlan& plan);

// The host side of a view: the plan's lights, its materials' parameters, their textures and the
// textures' images (views of the plan's pixels), and its triangle-primary meshes.
struct DirectPixelTables {
    std::vector<Light> lights;
    std::vector<PixelMaterial> materials;
    std::vector<TextureParams> textures;
    std::vector<ImageView> images;
    // Triangle primaries: the plan's meshes with their LBVHs, and the view of them (pointing into
    // `meshes`: the tables move but are not copied).
    MeshPrimaryTables meshes;
    MeshPrimaryView meshView;

    DirectPixelTables() = default;
    DirectPixelTables(DirectPixelTables&&) = default;
    DirectPixelTables& operator=(DirectPixelTables&&) = default;
    DirectPixelTables(const DirectPixelTables&) = delete;
    DirectPixelTables& operator=(const DirectPixelTables&) = delete;
};
DirectPixelTables directPixelTables(const RenderPlan& plan);

// The view of `plan` for one frame of a film `filmWidth` pixels wide, its arrays `tables`'s; both
// must outlive it.
DirectPixelView directPixelView(const RenderPlan& plan, const FrameView& frame,
                                const DirectPixelTables& tables, int filmWidth);

}  // namespace sdft
