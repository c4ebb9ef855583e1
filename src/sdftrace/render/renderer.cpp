#include "sdftrace/render/renderer.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>

#include "sdftrace/core/error.h"
#include "sdftrace/exec/progress.h"
#include "sdftrace/exec/thread_arena.h"
#include "sdftrace/math/camera.h"
#include "sdftrace/math/sampling.h"
#include "sdftrace/render/direct_pixel.h"
#include "sdftrace/render/light_batch.h"
#include "sdftrace/render/light_sample.h"
#include "sdftrace/render/normal_stencil.h"
#include "sdftrace/render/path_tracer.h"
#include "sdftrace/render/primary_pixel.h"
#include "sdftrace/render/whitted_pixel.h"
#include "sdftrace/trace/field_tracer.h"
#include "sdftrace/trace/grid_tracer.h"
#include "sdftrace/trace/minmax_buffer.h"

namespace sdft {

namespace {

struct TileScratch {
    PacketScratch packet;
    std::vector<RaySegment> segments;
    std::vector<TraceResult> results;
    std::vector<Ray> gridRays;  // a single grid's primary rays (tracePrimaryGrid)
    std::vector<float> gridTMin, gridTMax;
    std::vector<GridTraceResult> gridResults;
    std::vector<int> hitPixel;                   // tile-local index of each hit
    std::vector<size_t> hitFilm;                 // each hit's pixel in the film
    std::vector<MeshPrimary::Hit> triangleHits;  // hybrid mode: per pixel, t < inf on triangles
    std::vector<int> normalHits;                 // the hits whose normal is the field's gradient
    std::vector<Vec3> hitPoint, hitNormal;
    std::vector<Vec3> hitView;  // per hit: its primary ray's direction
    std::vector<float> x, y, z, f;
    std::vector<RaySegment> shadowSegments;
    std::vector<TraceResult> shadowResults;
    std::vector<int> shadowOwner;
    std::vector<SoftShadowRay> softRays;
    std::vector<SoftShadowResult> softResults;
    SoftShadowScratch soft;
    std::vector<Vec3> radiance;
    std::vector<PixelMaterial> materials;  // per hit
    std::vector<float> visible;            // per hit: the current light's visibility
    std::vector<int> seen;                 // per hit: the current light's shadow rays that reach it
    std::vector<float> shadow, ao;         // per hit: the first shadowing light's visibility; AO
    int x0 = 0, y0 = 0, tw = 0;            // the tile being rendered
    RenderStats stats;
};

class TileRenderer {
  public:
    TileRenderer(const RenderPlan& plan, const FrameView& view, Film& film)
        : m_plan(plan),
          m_view(view),
          m_tape(plan.tape),
          m_film(film),
          m_camera(view.camera),
          m_settings(plan.settings),
          m_tables(directPixelTables(plan)),
          m_pixel(directPixelView(plan, view, m_tables, film.width)),
          m_whittedTables(whittedPixelTables(plan)),
          m_whittedView(whittedPixelView(plan, m_whittedTables)) {
        m_primary = m_settings.trace;
        m_primary.pixelRadius = m_camera.pixelRadius();
        // Shadow rays need only a yes/no answer: plain threshold, relaxation kept, no refinement.
        m_shadow = m_pixel.shadowRay;  // hit or miss only: no root refinement
        if (plan.ddaGrid) {
            m_gridView = plan.ddaGrid->view();
            m_grid = &m_gridView;
            // The reconstruction at a DDA hit (TraceResult::value) feeds shadow-ray offsets,
            // Whitted rays and the error AOV; without any of them it is not computed.
            m_gridHitValue = m_settings.shadows || m_film.has(Aov::Error);
            for (const Material& m : plan.materials)
                m_gridHitValue |= m.kind != Material::Kind::Plastic;
            m_minMax = primaryMinMax(plan, m_camera);  // none where the settings turn it off
        }
        if (planHasWhitted(plan) &&
            m_settings.maxReflections + m_settings.maxRefractions > kWhittedMaxBouncesCpu)
            throw InputError(
                "render: max_reflections + max_refractions must be at most 128 (the options' "
                "ranges, 64 each, sum to it)");
        static_assert(kWhittedMaxBouncesCpu == 128);
        const ShadowMethod method = m_settings.shadowMethod;
        if (m_settings.shadows && (method == ShadowMethod::Pcf || method == ShadowMethod::Evsm)) {
            const Bounds3 region = shadowRegion();
            for (const Light& light : plan.lighting.lights) {
                m_maps.push_back(nullptr);
                if (!light.castShadows || region.empty()) continue;
                m_maps.back() = std::make_unique<ShadowMap>(
                    m_tape, light, region, m_settings.trace.secondary(),
                    method == ShadowMethod::Pcf ? ShadowMapFilter::Pcf : ShadowMapFilter::Evsm,
                    m_settings.shadowMap);
                m_mapEvaluations += m_maps.back()->evaluations();
            }
        }
    }

    uint64_t mapEvaluations() const { return m_mapEvaluations; }

    // The tile's pixels [x0, x1) x [y0, y1): trace, normals, shade, write the film.
    void renderTile(int x0, int y0, int x1, int y1, TileScratch& s);

  private:
    // Where shading points can lie: the scene's bounds, or (unbounded scenes) the bounds of the
    // hits of a coarse grid of primary rays, grown by a tenth.
    Bounds3 shadowRegion() const;
    // visible[h] in [0, 1]: how much of `light` hit h sees, by the settings' shadow method.
    void lightVisibility(TileScratch& s, std::vector<float>& visible, const Light& light,
                         int lightIndex);
    // Hard and distributed shadows: the hits' shadow rays (direct_pixel::shadowRays) as packets.
    void shadowRayVisibility(TileScratch& s, std::vector<float>& visible, const Light& light,
                             int lightIndex);
    // Traces s.shadowSegments into s.shadowResults (grid DDA or sphere-traced packets).
    void traceShadowSegments(TileScratch& s);
    // RTSDF soft shadows: the hits' marches (direct_pixel::softShadowRay) stepped together.
    void softShadows(TileScratch& s, std::vector<float>& visible, const Light& light,
                     int lightIndex);
    // One secondary hit's visibility of a light by a shadow map (Whitted rays' plastic hits).
    float mapVisibility(Vec3 p, Vec3 n, const Light& light, int lightIndex) const;
    // The shadow ray's origin offset along the normal (Keinert et al. 2014, §3.3).
    float shadowOffset(const TileScratch& s, int h) const {
        return direct_pixel::shadowOffset(m_pixel, s.results[s.hitPixel[h]].value);
    }
    // A pixel's index in the film, for seeding its random numbers.
    uint32_t pixelIndex(const TileScratch& s, int h) const {
        const int i = s.hitPixel[h];
        return direct_pixel::pixelSeed(m_pixel, s.x0 + i % s.tw, s.y0 + i / s.tw);
    }
    void tracePrimary(TileScratch& s, int x0, int y0, int x1, int y1);
    void tracePrimaryGrid(TileScratch& s, int x0, int y0, int tw);
    void tracePrimaryTriangles(TileScratch& s);
    void placeTriangleHits(TileScratch& s);
    void shadeDirect(TileScratch& s);
    void shadeSpecular(TileScratch& s);
    void writeFilm(const TileScratch& s);
    void gridNormals(TileScratch& s);
    void stencilNormals(TileScratch& s);

    const RenderPlan& m_plan;
    const FrameView& m_view;
    const Tape& m_tape;
    Film& m_film;
    Camera m_camera;
    const RenderSettings& m_settings;
    // The shading functions' view of the plan (direct_pixel.h, whitted_pixel.h): the GPU's.
    DirectPixelTables m_tables;
    DirectPixelView m_pixel;
    WhittedPixelTables m_whittedTables;
    WhittedPixelView m_whittedView;
    TraceOptions m_primary, m_shadow;
    // Set when the scene is a single grid traced by Jamriška's DDA (RenderSettings::gridTracer).
    const GridView* m_grid = nullptr;
    GridView m_gridView;
    bool m_gridHitValue = true;
    MinMaxBuffer m_minMax;  // Jamriška §6, built once per render; an empty view without one
    std::vector<std::unique_ptr<ShadowMap>> m_maps;  // per light, shadow-map methods
    uint64_t m_mapEvaluations = 0;
};

float TileRenderer::mapVisibility(Vec3 p, Vec3 n, const Light& light, int lightIndex) const {
    const LightDirection to = towardLight(light, p);
    if (dot(n, to.dir) <= 0) return 0.0f;
    const ShadowMap* map = m_maps[lightIndex].get();
    return map ? map->visibility(p, n) : 1.0f;
}

Bounds3 TileRenderer::shadowRegion() const {
    const Bounds3 all = m_tape.bounds();
    if (all.finite() && !all.empty()) return all;
    Bounds3 hits;
    const CameraDesc& d = m_camera.desc();
    const int nx = std::min(d.width, 160), ny = std::min(d.height, 120);
    TraceOptions opts = m_shadow;
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const Ray ray =
                m_camera.rayThrough((i + 0.5f) * d.width / nx, (j + 0.5f) * d.height / ny);
            const TraceResult r = traceRay(m_tape, {ray, 0.0f, m_settings.maxDistance}, opts);
            if (r.hit) hits.include(ray.at(r.t));
        }
    if (hits.empty()) return hits;
    return hits.expanded(0.1f * length(hits.extent()) + 1e-3f);
}

void TileRenderer::renderTile(int x0, int y0, int x1, int y1, TileScratch& s) {
    tracePrimary(s, x0, y0, x1, y1);
    if (m_grid) {
        gridNormals(s);
    } else {
        stencilNormals(s);
    }
    if (m_plan.meshPrimary) placeTriangleHits(s);
    shadeDirect(s);
    shadeSpecular(s);
    writeFilm(s);
}

// The tile's primary rays, traced as one packet (or by the grid DDA); the hits gathered.
void TileRenderer::tracePrimary(TileScratch& s, int x0, int y0, int x1, int y1) {
    const int tw = x1 - x0;
    const int count = tw * (y1 - y0);
    s.x0 = x0;
    s.y0 = y0;
    s.tw = tw;
    s.segments.resize(count);
    s.results.resize(count);
    for (int y = y0, i = 0; y < y1; ++y)
        for (int x = x0; x < x1; ++x, ++i)
            s.segments[i] = {primaryRay(m_camera, x, y, m_view.pixelJitter), 0.0f,
                             m_settings.maxDistance};
    if (m_grid) {
        tracePrimaryGrid(s, x0, y0, tw);
    } else if (m_plan.meshPrimary && !m_plan.primaryField) {
        std::fill(s.results.begin(), s.results.end(), TraceResult{});  // only meshes
    } else {
        tracePacket(m_plan.primaryField ? *m_plan.primaryField : m_tape, s.segments, m_primary,
                    s.results, s.packet);
        for (int i = 0; i < count; ++i)  // the top-level planes past the rest (horizon.h)
            meetHorizon(m_plan.horizon, s.segments[i].ray, s.results[i]);
    }
    if (m_plan.meshPrimary) tracePrimaryTriangles(s);
    s.hitPixel.clear();
    s.hitFilm.clear();
    s.hitPoint.clear();
    for (int y = y0, i = 0; y < y1; ++y) {
        const size_t row = static_cast<size_t>(y) * m_film.width;
        for (int x = x0; x < x1; ++x, ++i) {
            const TraceResult& r = s.results[i];
            s.stats.primaryEvaluations += r.evaluations;
            s.stats.fallbacks += r.fallbacks;
            if (!r.hit) continue;
            s.hitPixel.push_back(i);
            s.hitFilm.push_back(row + x);
            s.hitPoint.push_back(s.segments[i].ray.at(r.t));
        }
    }
    s.stats.primaryRays += count;
    s.stats.hits += s.hitPixel.size();
}

// Hybrid mode (RTSDF): each primary ray also against the meshes' triangles; a nearer triangle
// hit replaces the field's.
void TileRenderer::tracePrimaryTriangles(TileScratch& s) {
    const size_t count = s.segments.size();
    s.triangleHits.assign(count, MeshPrimary::Hit{});
    for (size_t i = 0; i < count; ++i) {
        TraceResult& r = s.results[i];
        const float tMax = r.hit ? r.t : s.segments[i].tMax;
        const MeshPrimary::Hit h = m_plan.meshPrimary->firstHit(s.segments[i].ray, tMax);
        if (!(h.t < tMax)) continue;
        r.hit = true;
        r.t = h.t;
        r.value = 0;
        s.triangleHits[i] = h;
    }
}

// Triangle hits shade with the triangle's normal, at a point one voxel of the mesh's grid off
// the triangle (RTSDF §2.5.3's bias): the SDF that shadows and AO march is a voxel's accuracy
// away from the triangles, and would shadow its own surface from below it.
void TileRenderer::placeTriangleHits(TileScratch& s) {
    for (size_t h = 0; h < s.hitPixel.size(); ++h) {
        const MeshPrimary::Hit& t = s.triangleHits[static_cast<size_t>(s.hitPixel[h])];
        if (!(t.t < INFINITY)) continue;
        s.hitNormal[h] = t.normal;
        s.hitPoint[h] += t.normal * t.bias;
    }
}

// The hits shaded by direct_pixel.h's functions, the GPU's: material, ambient (scaled by SDF
// ambient occlusion), and each light's Lambert + Blinn-Phong term where the shadow method lets it
// through; a tile's shadow rays and marches are traced together, light by light.
void TileRenderer::shadeDirect(TileScratch& s) {
    const int hits = static_cast<int>(s.hitPixel.size());
    s.radiance.resize(hits);
    s.materials.resize(hits);
    s.ao.resize(hits);
    s.hitView.resize(hits);
    // One material everywhere (materialAt's shortcut): the lights read it once.
    const bool oneMaterial =
        m_pixel.uniformMaterial >= 0 && m_pixel.uniformMaterial < m_pixel.materialCount;
    for (int h = 0; h < hits; ++h) {
        s.hitView[h] = s.segments[s.hitPixel[h]].ray.direction;
        s.materials[h] = oneMaterial ? m_pixel.materials[m_pixel.uniformMaterial]
                                     : direct_pixel::materialAt<kTapeMaxScalarRegs>(
                                           m_pixel, s.hitPoint[h], s.hitNormal[h]);
        uint32_t evaluations = 0;
        s.radiance[h] = direct_pixel::ambientLight(m_pixel, s.hitPoint[h], s.hitNormal[h],
                                                   s.materials[h], s.ao[h], evaluations);
        s.stats.aoEvaluations += evaluations;
    }
    std::vector<float>& visible = s.visible;
    s.shadow.assign(hits, 1.0f);
    bool firstShadow = true;
    for (size_t li = 0; li < m_plan.lighting.lights.size(); ++li) {
        const Light& light = m_plan.lighting.lights[li];
        visible.assign(hits, 1.0f);
        if (m_settings.shadows && light.castShadows) {
            lightVisibility(s, visible, light, static_cast<int>(li));
            if (firstShadow) s.shadow = visible;
            firstShadow = false;
        }
        if (!light.positional()) {
            addDirectionalLight(light, s.materials.data(), oneMaterial, s.hitNormal.data(),
                                s.hitView.data(), visible.data(), hits, s.radiance.data());
            continue;
        }
        for (int h = 0; h < hits; ++h)
            s.radiance[h] += direct_pixel::lightTerm(light, s.materials[h], s.hitPoint[h],
                                                     s.hitNormal[h], s.hitView[h], visible[h]);
    }
}

// Mirrors and dielectrics: Whitted rays from the hit (Keinert §4), by whitted_pixel.h's ray tree
// on a stack that holds every budget; secondary hits see the lights by the shadow method, shadow
// maps included.
void TileRenderer::shadeSpecular(TileScratch& s) {
    const int hits = static_cast<int>(s.hitPixel.size());
    const bool maps = m_settings.shadowMethod == ShadowMethod::Pcf ||
                      m_settings.shadowMethod == ShadowMethod::Evsm;
    const auto vis = [&](Vec3 p, Vec3 n, const Light& light, int li, uint32_t& evaluations) {
        return maps ? mapVisibility(p, n, light, li)
                    : secondaryVisibility(m_pixel.primary.field, m_whittedView.shadows, p, n, light,
                                          evaluations);
    };
    // The device's stack where the budget fits it (2 KB), else one for every budget (16 KB).
    const bool deep =
        m_whittedView.maxReflections + m_whittedView.maxRefractions > kWhittedMaxBounces;
    for (int h = 0; h < hits; ++h) {
        if (s.materials[h].kind == Material::Kind::Plastic) continue;
        const int i = s.hitPixel[h];
        WhittedCounters c;
        const Vec3 p = s.hitPoint[h], n = s.hitNormal[h], d = s.segments[i].ray.direction;
        const float f = s.results[i].value;
        s.radiance[h] = deep ? shadeWhitted<kTapeMaxScalarRegs, kWhittedStackCpu>(
                                   m_pixel, m_whittedView, p, n, f, d, s.materials[h], c, vis)
                             : shadeWhitted<kTapeMaxScalarRegs, kWhittedStack>(
                                   m_pixel, m_whittedView, p, n, f, d, s.materials[h], c, vis);
        s.stats.secondaryRays += c.rays;
        s.stats.secondaryEvaluations += c.evaluations;
        s.stats.selfIntersections += c.selfIntersections;
        s.stats.shadowEvaluations += c.shadowEvaluations;
    }
}

// Colour and AOVs of the tile: the background where rays missed; no NaN or Inf pixel.
void TileRenderer::writeFilm(const TileScratch& s) {
    const int count = static_cast<int>(s.results.size()), tw = s.tw;
    const int hits = static_cast<int>(s.hitPixel.size());
    const Vec3 bg = m_plan.lighting.background;
    // Only the AOVs the film keeps (Film's AOV set).
    const bool steps = m_film.has(Aov::Steps), normals = m_film.has(Aov::Normal),
               depth = m_film.has(Aov::Depth), error = m_film.has(Aov::Error),
               shadow = m_film.has(Aov::Shadow), ao = m_film.has(Aov::Ao);
    for (int i = 0, row = 0; i < count; i += tw, ++row) {
        const size_t p0 = static_cast<size_t>(s.y0 + row) * m_film.width + s.x0;
        for (int x = 0; x < tw; ++x) {
            const size_t p = p0 + x;
            m_film.color[3 * p + 0] = bg.x;
            m_film.color[3 * p + 1] = bg.y;
            m_film.color[3 * p + 2] = bg.z;
            if (steps) m_film.steps[p] = static_cast<float>(s.results[i + x].evaluations);
        }
    }
    for (int h = 0; h < hits; ++h) {
        const int i = s.hitPixel[h];
        const size_t p = s.hitFilm[h];
        Vec3 c = s.radiance[h];
        if (!isFinite(c)) c = Vec3(0.0f);
        for (int a = 0; a < 3; ++a) {
            m_film.color[3 * p + a] = c[a];
            if (normals) m_film.normal[3 * p + a] = s.hitNormal[h][a];
        }
        if (depth) m_film.depth[p] = s.results[i].t;
        if (error) m_film.error[p] = s.results[i].value;
        if (shadow) m_film.shadow[p] = s.shadow[h];
        if (ao) m_film.ao[p] = s.ao[h];
    }
}

// Normals: every stencil point of every hit in one batch.
void TileRenderer::stencilNormals(TileScratch& s) {
    const int hits = static_cast<int>(s.hitPixel.size());
    const NormalEstimator est = m_settings.normals;
    const int sn = stencilSize(est);
    // Hits on triangles (hybrid mode) take the triangle's normal (placeTriangleHits).
    std::vector<int>& todo = s.normalHits;
    todo.clear();
    for (int h = 0; h < hits; ++h)
        if (!m_plan.meshPrimary || !(s.triangleHits[s.hitPixel[h]].t < INFINITY)) todo.push_back(h);
    const int m = static_cast<int>(todo.size()) * sn;
    s.x.resize(m);
    s.y.resize(m);
    s.z.resize(m);
    s.f.resize(m);
    for (size_t j = 0; j < todo.size(); ++j) {
        const int h = todo[j];
        float t = s.results[s.hitPixel[h]].t;
        const float eps =
            primaryNormalSpacing(t, m_primary.pixelRadius, m_settings.normalSpacingMin);
        for (int k = 0; k < sn; ++k) {
            Vec3 q = s.hitPoint[h] + stencilOffset(est, k) * eps;
            s.x[j * sn + k] = q.x;
            s.y[j * sn + k] = q.y;
            s.z[j * sn + k] = q.z;
        }
    }
    m_tape.evalBatch(s.x.data(), s.y.data(), s.z.data(), s.f.data(), m, s.packet.batch);
    s.stats.normalEvaluations += m;
    s.hitNormal.resize(hits);
    for (size_t j = 0; j < todo.size(); ++j) {
        const int h = todo[j];
        Vec3 g(0.0f);
        for (int k = 0; k < sn; ++k) g += stencilOffset(est, k) * s.f[j * sn + k];
        Vec3 n = normalize(g);
        s.hitNormal[h] = normalOrFacing(n, s.segments[s.hitPixel[h]].ray.direction);
    }
}

// Jamriška 2010, §4: primary rays of a single-grid scene by two-level DDA; the counters go to the
// trav_steps and isect_tests AOVs.
void TileRenderer::tracePrimaryGrid(TileScratch& s, int x0, int y0, int tw) {
    const bool trav = m_film.has(Aov::TravSteps), isect = m_film.has(Aov::IsectTests);
    const size_t n = s.segments.size();
    s.gridRays.resize(n);
    s.gridTMin.resize(n);
    s.gridTMax.resize(n);
    s.gridResults.resize(n);
    const int rows = static_cast<int>(n) / tw;
    const MinMaxView minMax = m_minMax.view();
    for (int y = 0, i = 0; y < rows; ++y)
        for (int x = 0; x < tw; ++x, ++i) {
            const RaySegment& seg = s.segments[i];
            float t0, t1;  // [0, inf) without a buffer
            minMax.range(x0 + x, y0 + y, t0, t1);
            s.gridRays[i] = seg.ray;
            s.gridTMin[i] = std::max(seg.tMin, t0);
            s.gridTMax[i] = std::min(seg.tMax, t1);
        }
    // Eight neighbouring rays of a row at a time (packets through the DDA where AVX2 runs).
    traceGridRays(*m_grid, s.gridRays.data(), s.gridTMin.data(), s.gridTMax.data(),
                  static_cast<int>(n), m_settings.gridTrace, s.gridResults.data(),
                  m_pixel.primary.gridStartSign);
    for (int y = 0, i = 0; y < rows; ++y)
        for (int x = 0; x < tw; ++x, ++i) {
            const GridTraceResult& g = s.gridResults[i];
            TraceResult r;
            r.hit = g.hit;
            r.t = g.t;
            r.evaluations = g.interpolations;
            r.value =
                g.hit && m_gridHitValue ? m_grid->interpolate(s.segments[i].ray.at(g.t)) : 0.0f;
            s.results[i] = r;
            const size_t p = static_cast<size_t>(y0 + y) * m_film.width + (x0 + x);
            if (trav) m_film.travSteps[p] = static_cast<float>(g.traversalSteps);
            if (isect) m_film.isectTests[p] = static_cast<float>(g.intersectionTests);
            s.stats.traversalSteps += g.traversalSteps;
            s.stats.intersectionTests += g.intersectionTests;
        }
}

// Jamriška 2010, §5: one of the three gradient estimators on the grid's samples.
void TileRenderer::gridNormals(TileScratch& s) {
    int hits = static_cast<int>(s.hitPixel.size());
    s.hitNormal.resize(hits);
    for (int h = 0; h < hits; ++h) {
        const int i = s.hitPixel[h];
        const Vec3 n =
            gridHitNormal(*m_grid, s.gridResults[i], s.hitPoint[h], m_settings.gridNormals);
        s.hitNormal[h] = normalOrFacing(n, s.segments[i].ray.direction);
    }
}

void TileRenderer::shadowRayVisibility(TileScratch& s, std::vector<float>& visible,
                                       const Light& light, int lightIndex) {
    const int hits = static_cast<int>(visible.size());
    s.shadowSegments.clear();
    s.shadowOwner.clear();
    s.seen.resize(hits);
    int rays = 1;
    for (int h = 0; h < hits; ++h) {
        const direct_pixel::ShadowRayShare share = direct_pixel::shadowRays(
            m_pixel, light, lightIndex, s.hitPoint[h], s.hitNormal[h], shadowOffset(s, h),
            pixelIndex(s, h), [&](Vec3 origin, Vec3 dir, float tMax) {
                s.shadowSegments.push_back({{origin, dir}, 0.0f, tMax});
                s.shadowOwner.push_back(h);
            });
        s.seen[h] = share.seen;
        rays = share.rays;  // the same for every hit of the light
    }
    traceShadowSegments(s);
    for (size_t j = 0; j < s.shadowSegments.size(); ++j)
        s.seen[s.shadowOwner[j]] += !s.shadowResults[j].hit;
    for (int h = 0; h < hits; ++h) visible[h] = static_cast<float>(s.seen[h]) / rays;
}

void TileRenderer::traceShadowSegments(TileScratch& s) {
    s.shadowResults.resize(s.shadowSegments.size());
    if (m_grid) {
        // Jamriška §7: optionally the volumetric-occluder traversal.
        const bool trav = m_film.has(Aov::TravSteps), isect = m_film.has(Aov::IsectTests);
        for (size_t j = 0; j < s.shadowSegments.size(); ++j) {
            const RaySegment& seg = s.shadowSegments[j];
            GridTraceResult g = traceGridShadow(*m_grid, seg.ray, seg.tMin, seg.tMax,
                                                m_settings.gridTrace, m_settings.occluderThreshold);
            s.shadowResults[j] = TraceResult{g.hit, g.t, 0, g.interpolations, 0};
            int i = s.hitPixel[s.shadowOwner[j]];
            size_t p = static_cast<size_t>(s.y0 + i / s.tw) * m_film.width + (s.x0 + i % s.tw);
            if (trav) m_film.travSteps[p] += static_cast<float>(g.traversalSteps);
            if (isect) m_film.isectTests[p] += static_cast<float>(g.intersectionTests);
            s.stats.traversalSteps += g.traversalSteps;
            s.stats.intersectionTests += g.intersectionTests;
        }
    } else {
        tracePacket(m_tape, s.shadowSegments, m_shadow, s.shadowResults, s.packet);
    }
    for (const TraceResult& r : s.shadowResults) s.stats.shadowEvaluations += r.evaluations;
    s.stats.shadowRays += s.shadowSegments.size();
}

void TileRenderer::lightVisibility(TileScratch& s, std::vector<float>& visible, const Light& light,
                                   int lightIndex) {
    switch (m_settings.shadowMethod) {
        case ShadowMethod::Hard:
        case ShadowMethod::Distributed:
            shadowRayVisibility(s, visible, light, lightIndex);
            return;
        case ShadowMethod::Soft:
            softShadows(s, visible, light, lightIndex);
            return;
        case ShadowMethod::Pcf:
        case ShadowMethod::Evsm:
            for (size_t h = 0; h < visible.size(); ++h)
                visible[h] = mapVisibility(s.hitPoint[h], s.hitNormal[h], light, lightIndex);
            return;
    }
}

void TileRenderer::softShadows(TileScratch& s, std::vector<float>& visible, const Light& light,
                               int lightIndex) {
    s.softRays.clear();
    s.shadowOwner.clear();
    for (size_t h = 0; h < visible.size(); ++h) {
        const int hi = static_cast<int>(h);
        SoftShadowRay ray;
        if (!direct_pixel::softShadowRay(m_pixel, light, lightIndex, s.hitPoint[h], s.hitNormal[h],
                                         shadowOffset(s, hi), pixelIndex(s, hi), ray)) {
            visible[h] = 0;
            continue;
        }
        s.softRays.push_back(ray);
        s.shadowOwner.push_back(hi);
    }
    softShadowPacket(m_tape, s.softRays, m_pixel.soft, s.softResults, s.soft);
    for (size_t j = 0; j < s.softRays.size(); ++j) {
        visible[s.shadowOwner[j]] = s.softResults[j].visibility;
        s.stats.shadowEvaluations += s.softResults[j].evaluations;
    }
    s.stats.shadowRays += s.softRays.size();
}

}  // namespace

Vec3 estimateNormal(const Tape& tape, Vec3 p, float h, NormalEstimator estimator) {
    return estimateTapeNormal(tape.view(), p, h, estimator);
}

struct FrameRenderer::Impl {
    Impl(const RenderPlan& p, const FrameView& v, Film& f)
        : plan(p), view(v), film(f), arena(p.settings.threads) {}
    const RenderPlan& plan;
    const FrameView view;  // the renderers keep a reference to it
    Film& film;
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    ThreadArena arena;
    int tileSize = 16, tilesX = 0, tilesY = 0;
    std::unique_ptr<TileRenderer> direct;  // the direct-lighting renderer, or
    std::unique_ptr<PathFrame> paths;      // the path tracer
    tbb::enumerable_thread_specific<TileScratch> scratch;
    tbb::enumerable_thread_specific<RenderStats> pathStats;
};

namespace {
// A grid whose values are on the GPU (device_resident_grid.h) has only a stand-in on the host.
void requireHostGrids(const RenderPlan& plan) {
    if (!plan.deviceGrids.empty())
        throw InputError(
            "render: the plan's RTSDF grid lives on the GPU (--device cuda); the CPU renderer "
            "cannot read it");
}
}  // namespace

FrameRenderer::FrameRenderer(const RenderPlan& plan, const FrameView& view, Film& film)
    : m_impl((requireHostGrids(plan), std::make_unique<Impl>(plan, view, film))) {
    Impl& m = *m_impl;
    m.tileSize = std::max(1, plan.settings.tileSize);
    m.tilesX = (film.width + m.tileSize - 1) / m.tileSize;
    m.tilesY = (film.height + m.tileSize - 1) / m.tileSize;
    // Shadow maps render here, on the frame's threads.
    m.arena.execute([&] {
        if (plan.settings.pathTracing)
            m.paths = std::make_unique<PathFrame>(plan, m.view, film);
        else
            m.direct = std::make_unique<TileRenderer>(plan, m.view, film);
    });
}

FrameRenderer::~FrameRenderer() = default;

int FrameRenderer::tileCount() const { return m_impl->tilesX * m_impl->tilesY; }

PixelRect FrameRenderer::tile(int index) const {
    const Impl& m = *m_impl;
    const int tx = index % m.tilesX, ty = index / m.tilesX, ts = m.tileSize;
    return {tx * ts, ty * ts, std::min(m.film.width, (tx + 1) * ts),
            std::min(m.film.height, (ty + 1) * ts)};
}

void FrameRenderer::renderTiles(int first, int last, Progress* progress) {
    Impl& m = *m_impl;
    m.arena.execute([&] {
        tbb::parallel_for(
            tbb::blocked_range<int>(first, last, 1),
            [&](const tbb::blocked_range<int>& range) {
                for (int t = range.begin(); t != range.end(); ++t) {
                    const PixelRect r = tile(t);
                    if (m.paths) {
                        m.paths->render(r, m.pathStats.local());
                    } else {
                        m.direct->renderTile(r.x0, r.y0, r.x1, r.y1, m.scratch.local());
                    }
                    if (progress) progress->advance();
                }
            },
            tbb::simple_partitioner());
    });
}

RenderStats FrameRenderer::stats() const {
    const Impl& m = *m_impl;
    RenderStats total;
    for (const TileScratch& s : m.scratch) total.add(s.stats);
    for (const RenderStats& s : m.pathStats) total.add(s);
    if (m.direct) {
        total.shadowEvaluations += m.direct->mapEvaluations();
        total.gridTracer = m.plan.ddaGrid != nullptr;
    }
    total.threads = m.arena.threads();
    total.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - m.start).count();
    return total;
}

RenderStats render(const RenderPlan& plan, const FrameView& view, Film& film, bool progress) {
    requireHostGrids(plan);
    if (plan.settings.pathTracing) return renderPaths(plan, view, film, progress);
    FrameRenderer frame(plan, view, film);
    Progress bar("render", static_cast<uint64_t>(frame.tileCount()), progress);
    frame.renderTiles(0, frame.tileCount(), &bar);
    return frame.stats();
}

}  // namespace sdft
