#include "sdftrace/scene/render_options.h"

#include <cmath>
#include <cstdlib>
#include <sstream>

#include "sdftrace/core/macros.h"
#include "sdftrace/math/vec.h"

static_assert(sdft::kMaxOptionMagnitude == sdft::kMaxCoordinate);

namespace sdft {

namespace {

#define SDFT_MEMBER(m) SDFT_OPTION_MEMBER(RenderSettings, m)

constexpr double kInf = INFINITY;
constexpr OptionRange kPositive{0, kInf, true, true};
constexpr OptionRange kNonNegative{0, kInf, false, true};

std::vector<RenderOption> makeTable() {
    using T = OptionType;
    return {
        // Sphere tracing (Hart 1996; Keinert et al. 2014; Liktor 2008).
        {.key = "max_steps",
         .flags = "--max-steps",
         .group = "Tracer",
         .type = T::Int,
         .range = {1, 100000},
         .what = "an integer",
         .doc = "march evaluations per ray (Hart's MAX_ITERATIONS)",
         SDFT_MEMBER(trace.maxSteps)},
        {.key = "tau",
         .flags = "--tau",
         .group = "Tracer",
         .type = T::Float,
         .range = kPositive,
         .what = "a hit threshold",
         .doc = "hit threshold on f/L when `screen_space` is off",
         SDFT_MEMBER(trace.tau),
         .scaled = true},
        {.key = "omega",
         .flags = "--omega",
         .group = "Tracer",
         .type = T::Float,
         .range = {1, 2, false, true},
         .what = "an over-relaxation factor",
         .doc =
             "fixed over-relaxation with the safe fallback (Keinert et al. 2014, §3.1; 1 = off), "
             "when `adaptive_relaxation` is off",
         SDFT_MEMBER(trace.omega)},
        {.key = "adaptive_relaxation",
         .flags = "--adaptive-relaxation",
         .group = "Tracer",
         .type = T::Bool,
         .doc = "primary rays: each step's over-relaxation from the slope of the last two "
                "distances, up to 2, with the same safe fallback (Bálint & Valasek 2018)",
         SDFT_MEMBER(trace.adaptiveRelaxation)},
        {.key = "segment_tracing",
         .flags = "--segment-tracing",
         .group = "Tracer",
         .type = T::Bool,
         .doc = "camera rays: step by a bound on the field's slope along the segment ahead "
                "instead of its global Lipschitz bound, long steps along grazing floors and "
                "walls, no over-relaxation (Galin et al. 2020)",
         SDFT_MEMBER(trace.segmentTracing)},
        {.key = "screen_space",
         .flags = "--screen-space",
         .group = "Tracer",
         .type = T::Bool,
         .doc = "pick the point of smallest screen-space unbounding radius and stop under half a "
                "pixel (Keinert §3.2)",
         SDFT_MEMBER(trace.screenSpace)},
        {.key = "force_hit",
         .flags = "--force-hit",
         .group = "Tracer",
         .type = T::Bool,
         .doc = "keep the best candidate even if the march did not converge (Keinert §3.2)",
         SDFT_MEMBER(trace.forceHit)},
        {.key = "discontinuity_iterations",
         .flags = "--discontinuity-iterations,--discontinuity",
         .group = "Tracer",
         .type = T::Int,
         .range = {0, 64},
         .what = "an integer",
         .doc = "fixed-point iterations after the march (Keinert §3.4; 0 = off), one evaluation "
                "each per hit ray",
         SDFT_MEMBER(trace.discontinuityIters)},
        {.key = "fixed_steps",
         .flags = "--fixed-steps",
         .group = "Tracer",
         .type = T::Bool,
         .doc = "every ray takes exactly `max_steps` steps (Liktor 2008, §5.4)",
         SDFT_MEMBER(trace.fixedSteps)},
        {.key = "hybrid",
         .flags = "--hybrid",
         .group = "Tracer",
         .type = T::Bool,
         .doc = "sphere tracing, then linear search and regula falsi (Liktor §5.3-5.4)",
         SDFT_MEMBER(trace.hybrid)},
        {.key = "hybrid_epsilon",
         .flags = "--hybrid-epsilon",
         .group = "Tracer",
         .type = T::Float,
         .range = kPositive,
         .what = "a distance",
         .doc = "f/L under which the hybrid searches linearly",
         SDFT_MEMBER(trace.hybridEpsilon),
         .scaled = true},
        {.key = "hybrid_step",
         .flags = "--hybrid-step",
         .group = "Tracer",
         .type = T::Float,
         .range = kPositive,
         .what = "a step length",
         .doc = "the hybrid's linear step (features thinner than this can be stepped over)",
         SDFT_MEMBER(trace.hybridStep),
         .scaled = true},
        {.key = "falsi_iterations",
         .flags = "--falsi-iterations",
         .group = "Tracer",
         .type = T::Int,
         .range = {0, 64},
         .what = "an integer",
         .doc = "regula falsi iterations of the hybrid",
         SDFT_MEMBER(trace.falsiIters)},
        {.key = "root_iterations",
         .flags = "--root-iterations",
         .group = "Tracer",
         .type = T::Int,
         .range = {0, 16},
         .what = "an integer",
         .doc = "evaluations that move a hit onto the root of f (bracketed secant, Illinois regula "
                "falsi) for depth, position and normal; 0 = Keinert's placement",
         SDFT_MEMBER(trace.rootIters)},
        {.key = "max_distance",
         .flags = "--max-distance",
         .group = "Tracer",
         .type = T::Float,
         .range = kNonNegative,
         .what = "a distance",
         .doc = "t_max of primary rays (the scene bounds clip it further); 0: automatic, at least "
                "100 and past the scene's bounds from the camera at its distance from the target "
                "(top-level planes are met to the horizon beyond those of everything else)",
         .get = [](const RenderSettings& s) { return s.maxDistanceAuto ? 0.0 : s.maxDistance; },
         .set =
             [](RenderSettings& s, double v) {
                 s.maxDistanceAuto = v == 0;
                 s.maxDistance = v == 0 ? RenderSettings{}.maxDistance : fromOptionNumber<float>(v);
             }},
        {.key = "bounds_culling",
         .flags = "--bounds-culling",
         .group = "Tracer",
         .type = T::Bool,
         .doc = "skip union operands whose box is no nearer than the running minimum (decision "
                "0002; changes no hit)",
         SDFT_MEMBER(boundsCulling)},
        {.key = "pruning",
         .flags = "--pruning",
         .group = "Tracer",
         .type = T::Bool,
         .doc = "per cell of an octree over the scene, a tape without the operands that cannot "
                "change the field there (Lipschitz pruning, decision 0021; changes no hit)",
         SDFT_MEMBER(pruning)},
        // Shading and shadows (Liktor §4.1; RTSDF §2.4-2.5 and §3).
        {.key = "normals",
         .flags = "--normals",
         .group = "Shading",
         .type = T::Choice,
         .choices = {"central", "tetrahedral"},
         .doc = "gradient estimator: central differences (6 taps) or tetrahedral (4 taps)",
         SDFT_MEMBER(normals)},
        {.key = "shadows",
         .flags = "--shadows",
         .group = "Shading",
         .type = T::Bool,
         .doc = "lights with `shadows` cast them, by `shadow_method`",
         SDFT_MEMBER(shadows)},
        {.key = "shadow_method",
         .flags = "--shadow-method",
         .group = "Shading",
         .type = T::Choice,
         .choices = {"hard", "soft", "distributed", "pcf", "evsm"},
         .doc = "hard: one ray to the light's centre (Liktor §4.1); soft: SDF soft shadows, one "
                "march to where the ray leaves the scene (RTSDF §2.4-2.5); distributed: rays to "
                "stratified points on the light, the "
                "ground truth; pcf, evsm: shadow maps traced from the light",
         SDFT_MEMBER(shadowMethod)},
        {.key = "shadow_rays",
         .flags = "--shadow-rays",
         .group = "Shading",
         .type = T::Int,
         .range = {1, 65536},
         .what = "an integer",
         .doc = "distributed: rays per point and light (a per-pixel rotated Halton sequence)",
         SDFT_MEMBER(shadowRays)},
        {.key = "shadow_offset",
         .flags = "--shadow-offset",
         .group = "Shading",
         .type = T::Float,
         .range = kPositive,
         .what = "a distance",
         .doc = "eps_min of the shadow- and secondary-ray origin offset 2 max(eps_min, |f(p)|) "
                "(Keinert §3.3)",
         SDFT_MEMBER(shadowOffsetMin),
         .scaled = true},
        {.key = "soft_max_step",
         .flags = "--soft-max-step",
         .group = "Shading",
         .type = T::Float,
         .range = kNonNegative,
         .what = "a distance",
         .doc = "soft: the largest march step (RTSDF §2.5.2 uses 0.05; 0 = unlimited)",
         SDFT_MEMBER(soft.maxStep),
         .scaled = true},
        {.key = "soft_bias",
         .flags = "--soft-bias",
         .group = "Shading",
         .type = T::Float,
         .range = kNonNegative,
         .what = "a distance",
         .doc = "soft: subtracted from every distance, thickening thin surfaces (RTSDF §2.5.3)",
         SDFT_MEMBER(soft.bias),
         .scaled = true},
        {.key = "soft_triangulation",
         .flags = "--soft-triangulation",
         .group = "Shading",
         .type = T::Bool,
         .doc = "soft: Aaltonen's estimate from two consecutive samples (RTSDF fig. 8), where "
                "it falls between them; off: k·h/t",
         SDFT_MEMBER(soft.triangulate)},
        {.key = "soft_jitter",
         .flags = "--soft-jitter",
         .group = "Shading",
         .type = T::Bool,
         .doc = "soft: per-pixel random start within one max step",
         SDFT_MEMBER(soft.jitter)},
        {.key = "soft_centered",
         .flags = "--soft-centered",
         .group = "Shading",
         .type = T::Bool,
         .doc = "soft: march on through occluders so the penumbra straddles the hard edge; off: "
                "RTSDF's estimate (penumbrae widen outwards)",
         SDFT_MEMBER(soft.centered)},
        {.key = "shadow_map_resolution",
         .flags = "--shadow-map-resolution",
         .group = "Shading",
         .type = T::Int,
         .range = {16, 8192},
         .what = "an integer",
         .doc = "pcf, evsm: texels along the map's side (cube faces: half)",
         SDFT_MEMBER(shadowMap.resolution)},
        {.key = "pcf_radius",
         .flags = "--pcf-radius",
         .group = "Shading",
         .type = T::Int,
         .range = {0, 64},
         .what = "an integer",
         .doc = "pcf: (2r+1)² depth tests",
         SDFT_MEMBER(shadowMap.pcfRadius)},
        {.key = "evsm_radius",
         .flags = "--evsm-radius",
         .group = "Shading",
         .type = T::Int,
         .range = {0, 64},
         .what = "an integer",
         .doc = "evsm: box filter of (2r+1)² texels (15 × 15 as RTSDF fig. 14)",
         SDFT_MEMBER(shadowMap.evsmRadius)},
        {.key = "ao",
         .flags = "--ao",
         .group = "Shading",
         .type = T::Bool,
         .doc = "SDF ambient occlusion on the ambient term",
         SDFT_MEMBER(ambientOcclusion)},
        {.key = "ao_samples",
         .flags = "--ao-samples",
         .group = "Shading",
         .type = T::Int,
         .range = {1, 64},
         .what = "an integer",
         .doc = "ao: samples along the normal",
         SDFT_MEMBER(ao.samples)},
        {.key = "ao_step",
         .flags = "--ao-step",
         .group = "Shading",
         .type = T::Float,
         .range = kPositive,
         .what = "a distance",
         .doc = "ao: spacing of the samples",
         SDFT_MEMBER(ao.step),
         .scaled = true},
        {.key = "ao_strength",
         .flags = "--ao-strength",
         .group = "Shading",
         .type = T::Float,
         .range = kNonNegative,
         .what = "a weight",
         .doc = "ao: weight of the occlusion",
         SDFT_MEMBER(ao.strength)},
        // Whitted mirrors and glass (Keinert §4, §3.3, §3.5).
        {.key = "max_reflections",
         .flags = "--max-reflections",
         .group = "Whitted",
         .type = T::Int,
         .range = {0, 64},
         .what = "an integer",
         .doc = "reflection bounces per ray (mirrors and Fresnel reflection)",
         SDFT_MEMBER(maxReflections)},
        {.key = "max_refractions",
         .flags = "--max-refractions",
         .group = "Whitted",
         .type = T::Int,
         .range = {0, 64},
         .what = "an integer",
         .doc = "refraction bounces per ray (entering, leaving, internal reflection)",
         SDFT_MEMBER(maxRefractions)},
        {.key = "secondary_epsilon",
         .flags = "--secondary-epsilon,--epsilon",
         .group = "Whitted",
         .type = T::Choice,
         .choices = {"dynamic", "global"},
         .doc = "secondary-ray origin offset: dynamic, 2 max(eps_min, |f(p)|) (Keinert §3.3), or "
                "global (`global_epsilon` along the normal)",
         .get = [](const RenderSettings& s) { return s.dynamicEpsilon ? 0.0 : 1.0; },
         .set = [](RenderSettings& s, double v) { s.dynamicEpsilon = v == 0; }},
        {.key = "global_epsilon",
         .flags = "--global-epsilon",
         .group = "Whitted",
         .type = T::Float,
         .range = kPositive,
         .what = "a distance",
         .doc = "the offset along the normal when `secondary_epsilon` is global",
         SDFT_MEMBER(globalEpsilon),
         .scaled = true},
        {.key = "convex_bounds",
         .flags = "--convex-bounds",
         .group = "Whitted",
         .type = T::Bool,
         .doc = "rays inside a convex top-level object jump to its bounding box and trace back on "
                "its own field (Keinert §3.5)",
         SDFT_MEMBER(convexBounds)},
        {.key = "primary_triangles",
         .flags = "--primary-triangles",
         .group = "Tracer",
         .type = T::Bool,
         .doc = "RTSDF's hybrid mode: primary rays hit mesh objects' triangles (Embree on the "
                "CPU, an LBVH per mesh under `--device cuda`), shadows and AO march their SDFs, "
                "the shading point biased one voxel off the triangle "
                "(RTSDF §2.5.3); meshes under operators other than union and transforms stay SDFs",
         SDFT_MEMBER(primaryTriangles)},
        // The integrator.
        {.key = "integrator",
         .flags = "--integrator",
         .group = "Path",
         .type = T::Choice,
         .choices = {"direct", "path"},
         .doc = "direct: direct lighting, shadows by `shadow_method`, Whitted mirrors and glass; "
                "path: a path tracer with next-event estimation (Keinert fig. 1)",
         SDFT_MEMBER(pathTracing)},
        {.key = "spp",
         .flags = "--spp",
         .group = "Path",
         .type = T::Int,
         .range = {1, 1 << 20},
         .what = "an integer",
         .doc = "path: paths per pixel (and per frame with --frames)",
         SDFT_MEMBER(samplesPerPixel)},
        {.key = "max_depth",
         .flags = "--max-depth",
         .group = "Path",
         .type = T::Int,
         .range = {1, 1024},
         .what = "an integer",
         .doc = "path: scattering events per path (1: direct light only)",
         SDFT_MEMBER(maxDepth)},
        // Single-grid scenes (Jamriška 2010).
        {.key = "grid_tracer",
         .flags = "--grid-tracer",
         .group = "Grids",
         .type = T::Choice,
         .choices = {"dda", "sphere"},
         .doc = "single-grid scenes: two-level 3D-DDA over blocks and cells (Jamriška §4) or "
                "sphere tracing",
         SDFT_MEMBER(gridTracer)},
        {.key = "cell_intersection",
         .flags = "--cell-intersection,--cell",
         .group = "Grids",
         .type = T::Choice,
         .choices = {"midpoint", "false-position"},
         .doc = "surface-cell intersection (Jamriška §4.2)",
         SDFT_MEMBER(gridTrace.cellMethod)},
        {.key = "cell_iterations",
         .flags = "--cell-iterations",
         .group = "Grids",
         .type = T::Int,
         .range = {1, 16},
         .what = "an integer",
         .doc = "false-position iterations (§4.2)",
         SDFT_MEMBER(gridTrace.falsiIters)},
        {.key = "bit_masks",
         .flags = "--bit-masks",
         .group = "Grids",
         .type = T::Bool,
         .doc = "test the per-block cell masks instead of the 8 corner signs (§4.1)",
         SDFT_MEMBER(gridTrace.bitMasks)},
        {.key = "ray_packets",
         .flags = "--ray-packets",
         .group = "Grids",
         .type = T::Bool,
         .doc = "DDA primary rays eight at a time in AVX2 registers, with the same hits as one by "
                "one (off: one by one)",
         SDFT_MEMBER(gridTrace.packets)},
        {.key = "grid_normals",
         .flags = "--grid-normals",
         .group = "Grids",
         .type = T::Choice,
         .choices = {"analytic", "difference-of-interpolations", "interpolation-of-differences"},
         .doc = "gradient estimator (§5)",
         SDFT_MEMBER(gridNormals)},
        {.key = "minmax_resolution",
         .flags = "--minmax-resolution,--minmax",
         .group = "Grids",
         .type = T::Int,
         .range = {0, 4096},
         .what = "an integer",
         .doc = "min/max-buffer pixels along the longer image side for primary rays (§6; 0 = off)",
         SDFT_MEMBER(minMaxResolution)},
        {.key = "occluder_threshold",
         .flags = "--occluder-threshold,--occluder",
         .group = "Grids",
         .type = T::Int,
         .range = {0, 100000},
         .what = "an integer",
         .doc = "shadow rays by volumetric occluders, restarting after n blocks (§7; 0 = off)",
         SDFT_MEMBER(occluderThreshold)},
    };
}

#undef SDFT_MEMBER

}  // namespace

std::span<const RenderOption> renderOptions() {
    static const std::vector<RenderOption> table = makeTable();
    static_assert(sizeof(RenderSettings::given) * 8 >= 64);
    SDFT_CHECK(table.size() <= 64);  // RenderSettings::given holds a bit per option
    return table;
}

void RenderOption::give(RenderSettings& s, double v) const {
    set(s, v);
    const auto all = renderOptions();
    s.given |= uint64_t{1} << (this - all.data());
}

float sceneLengthFactor(const Bounds3& bounds, const CameraDesc& camera) {
    const float length = bounds.finite() && !bounds.empty()
                             ? sdft::length(bounds.extent())
                             : sdft::length(camera.eye - camera.target);
    return length > 0 && length < 1 ? length : 1.0f;
}

void scaleLengthDefaults(RenderSettings& s, float factor) {
    const RenderSettings defaults;
    const auto all = renderOptions();
    for (size_t i = 0; i < all.size(); ++i)
        if (all[i].scaled && !(s.given >> i & 1)) all[i].set(s, all[i].get(defaults) * factor);
    // Lengths no option sets: the soft shadow's hit distance, the normals' smallest spacing.
    s.soft.epsilon = defaults.soft.epsilon * factor;
    s.normalSpacingMin = defaults.normalSpacingMin * factor;
}

const RenderOption* findRenderOption(const std::string& key) {
    for (const RenderOption& o : renderOptions())
        if (key == o.key) return &o;
    return nullptr;
}

std::string RenderOption::mainFlag() const { return mainFlagOf(flags); }

std::string renderOptionsMarkdown() {
    std::string md =
        "| key | flag | default | accepted | meaning |\n| --- | --- | --- | --- | --- |\n";
    for (const RenderOption& o : renderOptions()) {
        std::string flag = markdownCode(o.mainFlag());
        if (o.type == OptionType::Bool) {
            flag += " / ";
            flag += markdownCode("--no-" + o.mainFlag().substr(2));
        }
        md += markdownRow({markdownCode(o.key), flag, markdownCode(o.defaultText()),
                           markdownCell(o.accepted()), markdownCell(o.doc)});
    }
    return md;
}

}  // namespace sdft
