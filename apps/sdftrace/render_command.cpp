// sdftrace render [scene.json] -o image.png [--aov NAME=PATH]... [camera, tracer, shading flags]
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>

#include "commands.h"
#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/core/error.h"
#include "sdftrace/exec/progress.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/io/atomic_file.h"
#include "sdftrace/io/grid_file.h"
#include "sdftrace/io/image_io.h"
#include "sdftrace/io/mesh_file.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/render/temporal.h"
#include "sdftrace/scene/grid_scene.h"
#include "sdftrace/scene/option_names.h"
#include "sdftrace/scene/parse_scene.h"

namespace sdft::cli {

namespace {

struct RenderArgs {
    std::string scene;
    std::string output = "render.png";
    std::vector<std::string> aovs;
    std::string eye, target, up;
    std::optional<float> fov;
    std::optional<int> width, height, threads;
    // tracer
    bool classic = false;
    std::optional<int> maxSteps, discontinuity, falsiIters;
    std::optional<float> tau, omega, hybridEpsilon, hybridStep, maxDistance;
    // On/off switches: applied only when given (CLI11 would reset a std::optional<bool> flag).
    struct Switch {
        bool value = false;
        CLI::Option* option = nullptr;
        bool given() const { return option && option->count() > 0; }
    };
    Switch screenSpace, forceHit, fixedSteps, hybrid, shadows, boundsCulling, bitMasks;
    std::string normals;
    std::string gridTracer, cellMethod, gridNormals;
    std::string shadowMethod;
    std::optional<int> shadowRays, maxReflections, maxRefractions;
    std::string integrator;
    std::optional<int> spp, maxDepth;
    std::string epsilon;
    std::optional<float> globalEpsilon;
    int frames = 1;
    std::optional<float> taaAlpha;
    float orbit = 0;
    std::string framePattern;
    Switch ao, convexBounds;
    std::optional<int> cellIterations, occluder, minMax;
    bool quiet = false;
};

Vec3 toVec3(const Vec3Arg& a) { return {a.x, a.y, a.z}; }

void applyOverrides(const RenderArgs& a, Scene& scene) {
    CameraDesc& cam = scene.camera;
    if (!a.eye.empty()) cam.eye = toVec3(parseVec3Arg("--eye", a.eye));
    if (!a.target.empty()) cam.target = toVec3(parseVec3Arg("--target", a.target));
    if (!a.up.empty()) cam.up = toVec3(parseVec3Arg("--up", a.up));
    if (a.fov) cam.fovDeg = *a.fov;
    if (a.width) cam.width = *a.width;
    if (a.height) cam.height = *a.height;
    if (length(cam.target - cam.eye) <= 0)
        throw InputError("--eye/--target: the eye must differ from the target");
    if (length(cross(normalize(cam.target - cam.eye), cam.up)) < 1e-6f) {
        throw InputError("--up: must not be parallel to the viewing direction");
    }
    validateImageSize(cam.width, cam.height, "--width/--height");

    RenderSettings& s = scene.settings;
    TraceOptions& t = s.trace;
    if (a.classic) t = TraceOptions::classic();
    if (a.maxSteps) t.maxSteps = *a.maxSteps;
    if (a.tau) t.tau = *a.tau;
    if (a.omega) t.omega = *a.omega;
    if (a.screenSpace.given()) t.screenSpace = a.screenSpace.value;
    if (a.forceHit.given()) t.forceHit = a.forceHit.value;
    if (a.discontinuity) t.discontinuityIters = *a.discontinuity;
    if (a.fixedSteps.given()) t.fixedSteps = a.fixedSteps.value;
    if (a.hybrid.given()) t.hybrid = a.hybrid.value;
    if (a.hybridEpsilon) t.hybridEpsilon = *a.hybridEpsilon;
    if (a.hybridStep) t.hybridStep = *a.hybridStep;
    if (a.falsiIters) t.falsiIters = *a.falsiIters;
    if (!a.gridTracer.empty()) parseGridTracer(a.gridTracer, s.gridTracer);
    if (!a.cellMethod.empty()) parseCellIntersection(a.cellMethod, s.gridTrace.cellMethod);
    if (!a.gridNormals.empty()) parseGridNormal(a.gridNormals, s.gridNormals);
    if (a.cellIterations) s.gridTrace.falsiIters = *a.cellIterations;
    if (a.occluder) s.occluderThreshold = *a.occluder;
    if (a.minMax) s.minMaxResolution = *a.minMax;
    if (a.bitMasks.given()) s.gridTrace.bitMasks = a.bitMasks.value;
    if (a.normals == "central") s.normals = NormalEstimator::Central;
    if (a.normals == "tetrahedral") s.normals = NormalEstimator::Tetrahedral;
    if (a.shadows.given()) s.shadows = a.shadows.value;
    if (!a.shadowMethod.empty()) parseShadowMethod(a.shadowMethod, s.shadowMethod);
    if (a.shadowRays) s.shadowRays = *a.shadowRays;
    if (a.maxReflections) s.maxReflections = *a.maxReflections;
    if (!a.integrator.empty()) s.pathTracing = a.integrator == "path";
    if (a.spp) s.samplesPerPixel = *a.spp;
    if (a.maxDepth) s.maxDepth = *a.maxDepth;
    if (a.maxRefractions) s.maxRefractions = *a.maxRefractions;
    if (!a.epsilon.empty()) s.dynamicEpsilon = a.epsilon == "dynamic";
    if (a.globalEpsilon) s.globalEpsilon = *a.globalEpsilon;
    if (a.convexBounds.given()) s.convexBounds = a.convexBounds.value;
    if (a.ao.given()) s.ambientOcclusion = a.ao.value;
    if (a.boundsCulling.given()) s.boundsCulling = a.boundsCulling.value;
    if (a.maxDistance) s.maxDistance = *a.maxDistance;
    if (a.threads) s.threads = *a.threads;
}

// The path of frame k from a pattern holding one printf integer field (%d, %04d, ...).
std::string framePath(const std::string& pattern, int k) {
    std::vector<char> buf(pattern.size() + 32);
    std::snprintf(buf.data(), buf.size(), pattern.c_str(), k);
    return buf.data();
}

void validateFramePattern(const std::string& pattern) {
    // Exactly one conversion, an integer one: %d with an optional zero-padded width.
    size_t at = pattern.find('%'), count = 0;
    bool ok = true;
    while (at != std::string::npos) {
        size_t i = at + 1;
        if (i < pattern.size() && pattern[i] == '%') {
            at = pattern.find('%', i + 1);
            continue;
        }
        while (i < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[i]))) ++i;
        ok = ok && i < pattern.size() && pattern[i] == 'd' && i - at <= 4;
        ++count;
        at = pattern.find('%', i + 1);
    }
    if (!ok || count != 1) {
        throw InputError("--frame-pattern " + pattern +
                         ": expected one frame-number field such as %d or %04d, e.g. out_%04d.png");
    }
    imageFormatFromPath(framePath(pattern, 0), "--frame-pattern");
    checkWritablePath(framePath(pattern, 0), "--frame-pattern");
}

int runRender(const RenderArgs& a) {
    // Validate every output before the (possibly long) render starts.
    imageFormatFromPath(a.output, "--output");
    checkWritablePath(a.output, "--output");
    if (!a.framePattern.empty()) validateFramePattern(a.framePattern);
    std::vector<std::pair<Aov, std::string>> aovs;
    for (const std::string& spec : a.aovs) {
        auto eq = spec.find('=');
        Aov aov;
        if (eq == std::string::npos || !parseAov(spec.substr(0, eq), aov) ||
            eq + 1 == spec.size()) {
            throw InputError(
                "--aov " + spec +
                ": expected NAME=PATH with NAME one of color, depth, normal, steps, error, "
                "trav_steps, isect_tests, shadow, ao");
        }
        std::string path = spec.substr(eq + 1);
        imageFormatFromPath(path, "--aov " + spec.substr(0, eq));
        checkWritablePath(path, "--aov " + spec.substr(0, eq));
        aovs.emplace_back(aov, path);
    }

    Scene scene;
    if (a.scene.empty()) {
        scene = demoScene();
    } else if (isMeshFile(a.scene)) {
        // A mesh rendered directly: baked exactly at the default resolution first.
        MeshReport report;
        TriangleMesh mesh = loadMesh(a.scene, &report);
        auto grid = std::make_shared<const Grid>(bakeMesh(mesh, MeshBakeOptions{}).grid);
        std::fprintf(stderr, "sdftrace render: %s: %s; baked exactly at 128 cells\n",
                     a.scene.c_str(), report.summary().c_str());
        scene = sceneForObject(node::grid(grid), grid->surfaceBounds());
    } else if (isGridFile(a.scene)) {
        // A grid file rendered directly: framed by an automatic camera, lit by default lights.
        auto grid = std::make_shared<const Grid>(loadGridFile(a.scene));
        Bounds3 frame = grid->surfaceBounds();
        if (frame.empty())
            throw InputError(a.scene + ": the grid contains no surface (no sign change)");
        scene = sceneForObject(node::grid(grid), frame);
    } else {
        scene = parseSceneFile(a.scene);
    }
    applyOverrides(a, scene);
    Tape tape = compileTape(scene.root, {.boundsCulling = scene.settings.boundsCulling});
    Film film(scene.camera.width, scene.camera.height);
    RenderStats st;
    if (a.frames > 1 || a.orbit != 0) {
        TemporalOptions t;
        t.frames = a.frames;
        t.orbitDegrees = a.orbit;
        if (a.taaAlpha) t.alpha = *a.taaAlpha;
        std::function<void(int, const Film&)> onFrame;
        if (!a.framePattern.empty()) {
            onFrame = [&](int k, const Film& f) {
                writeAov(f, Aov::Color, framePath(a.framePattern, k));
            };
        }
        st = renderFrames(scene, tape, film, t, onFrame, !a.quiet && stderrIsTerminal());
    } else {
        st = render(scene, tape, film, !a.quiet && stderrIsTerminal());
    }

    writeAov(film, Aov::Color, a.output);
    for (const auto& [aov, path] : aovs) writeAov(film, aov, path);

    double rays = static_cast<double>(st.primaryRays);
    if (scene.settings.pathTracing) {
        const double rayCount =
            static_cast<double>(st.primaryRays + st.secondaryRays + st.shadowRays);
        std::fprintf(stderr,
                     "sdftrace render: %dx%d path traced, %.0f paths per pixel, in %.3f s on %d "
                     "threads, %.3f Mpaths/s, %.2f rays per path (%.2f shadow rays), %.2f "
                     "evaluations per path, L = %.3g\n",
                     film.width, film.height, rays / static_cast<double>(film.pixels()), st.seconds,
                     st.threads, rays / st.seconds * 1e-6, rayCount / rays, st.shadowRays / rays,
                     st.totalEvaluations() / rays, tape.lipschitz());
        return 0;
    }
    std::string gridCounters;
    if (st.gridTracer) {
        char buf[160];
        std::snprintf(buf, sizeof buf,
                      ", DDA: %.2f traversal steps and %.2f intersection tests per pixel",
                      st.traversalSteps / rays, st.intersectionTests / rays);
        gridCounters = buf;
    }
    if (st.secondaryRays) {
        char buf[160];
        std::snprintf(
            buf, sizeof buf, ", Whitted: %.2f secondary rays per pixel, %llu self-intersections",
            st.secondaryRays / rays, static_cast<unsigned long long>(st.selfIntersections));
        gridCounters += buf;
    }
    std::fprintf(
        stderr,
        "sdftrace render: %dx%d in %.3f s on %d threads, %.3f Mrays/s, %.2f evaluations per "
        "primary ray (%.2f per pixel with normals and shadows), %.2f%% hits, %llu "
        "over-relaxation fallbacks, L = %.3g%s\n",
        film.width, film.height, st.seconds, st.threads, rays / st.seconds * 1e-6,
        st.primaryEvaluations / rays, st.totalEvaluations() / rays, 100.0 * st.hits / rays,
        static_cast<unsigned long long>(st.fallbacks), tape.lipschitz(), gridCounters.c_str());
    return 0;
}

}  // namespace

void addRenderCommand(CLI::App& app, Action& action) {
    auto args = std::make_shared<RenderArgs>();
    CLI::App* cmd = app.add_subcommand(
        "render",
        "Ray trace a scene file (or the built-in demo scene when none is given) to an image");
    cmd->add_option("scene", args->scene,
                    "Scene file (JSON, see docs/scene-format.md) or grid file (.sdfg, framed "
                    "automatically); default: the demo");
    cmd->add_option("-o,--output", args->output,
                    "Output image: .png (tone-mapped sRGB), .exr or .pfm (linear)")
        ->capture_default_str();
    cmd->add_option(
        "--aov", args->aovs,
        "Extra output NAME=PATH, repeatable. NAME: color (linear radiance), depth (t along the "
        "unit primary ray, inf on a miss), normal, steps (field evaluations of the primary "
        "ray), error (f at the hit point), trav_steps and isect_tests (grid DDA), shadow (the "
        "first shadowing light's visibility), ao (ambient occlusion). PATH: .exr, .pfm, or .png "
        "(heat map with legend)");
    auto* camera = cmd->add_option_group("Camera", "Override the scene's camera");
    camera->add_option("--eye", args->eye, "Camera position x,y,z");
    camera->add_option("--target", args->target, "Point looked at x,y,z");
    camera->add_option("--up", args->up, "Up vector x,y,z");
    camera->add_option("--fov", args->fov, "Vertical field of view in degrees, in (0, 180)")
        ->check(CLI::Range(1e-3, 179.999));
    camera->add_option("--width", args->width, "Image width in pixels")
        ->check(CLI::Range(1, 65536));
    camera->add_option("--height", args->height, "Image height in pixels")
        ->check(CLI::Range(1, 65536));

    auto* tracer = cmd->add_option_group(
        "Tracer", "Sphere tracing switches (override the scene's render block)");
    tracer->add_flag(
        "--classic", args->classic,
        "Plain sphere tracing (Hart): omega 1, no screen-space selection, no discontinuity "
        "reduction; later flags still apply");
    tracer->add_option("--max-steps", args->maxSteps, "March evaluations per ray")
        ->check(CLI::Range(1, 100000));
    tracer->add_option("--tau", args->tau, "Hit threshold on f/L (without screen-space selection)")
        ->check(CLI::PositiveNumber);
    tracer
        ->add_option("--omega", args->omega,
                     "Over-relaxation factor in [1, 2) (Keinert §3.1; 1 = off)")
        ->check(CLI::Range(1.0, 1.999999));
    args->screenSpace.option = tracer->add_flag(
        "--screen-space,!--no-screen-space", args->screenSpace.value,
        "Screen-space intersection selection and half-pixel early exit (Keinert §3.2)");
    args->forceHit.option = tracer->add_flag(
        "--force-hit,!--no-force-hit", args->forceHit.value,
        "Use the best candidate even when the march did not converge (Keinert §3.2)");
    tracer
        ->add_option("--discontinuity", args->discontinuity,
                     "Fixed-point iterations after the march (Keinert §3.4; 0 = off)")
        ->check(CLI::Range(0, 64));
    args->fixedSteps.option =
        tracer->add_flag("--fixed-steps,!--no-fixed-steps", args->fixedSteps.value,
                         "Every ray takes exactly --max-steps steps (Liktor §5.4)");
    args->hybrid.option = tracer->add_flag(
        "--hybrid,!--no-hybrid", args->hybrid.value,
        "Sphere tracing / linear search hybrid with regula falsi (Liktor §5.3-5.4)");
    tracer
        ->add_option("--hybrid-epsilon", args->hybridEpsilon,
                     "Distance under which the hybrid searches linearly")
        ->check(CLI::PositiveNumber);
    tracer->add_option("--hybrid-step", args->hybridStep, "Linear-search step of the hybrid")
        ->check(CLI::PositiveNumber);
    tracer
        ->add_option("--falsi-iterations", args->falsiIters,
                     "Regula falsi iterations of the hybrid")
        ->check(CLI::Range(0, 64));
    args->boundsCulling.option =
        tracer->add_flag("--bounds-culling,!--no-bounds-culling", args->boundsCulling.value,
                         "Skip union operands whose bounding box is no nearer than the running "
                         "minimum (decision 0002)");
    tracer->add_option("--max-distance", args->maxDistance, "Largest t of a primary ray")
        ->check(CLI::PositiveNumber);

    auto* shading = cmd->add_option_group("Shading");
    shading
        ->add_option("--integrator", args->integrator,
                     "direct (direct lighting, shadows by --shadow-method, Whitted mirrors and "
                     "glass) or path (a path tracer with next-event estimation; Keinert fig. 1)")
        ->check(CLI::IsMember({"direct", "path"}));
    shading->add_option("--spp", args->spp, "path: samples (paths) per pixel and frame")
        ->check(CLI::Range(1, 1 << 20));
    shading
        ->add_option("--max-depth", args->maxDepth,
                     "path: scattering events per path (1: direct light only)")
        ->check(CLI::Range(1, 1024));
    shading
        ->add_option("--normals", args->normals,
                     "Gradient estimator: central (6 taps) or tetrahedral (4 taps)")
        ->check(CLI::IsMember({"central", "tetrahedral"}));
    args->shadows.option = shading->add_flag("--shadows,!--no-shadows", args->shadows.value,
                                             "Shadows of the lights that cast them");
    shading
        ->add_option("--shadow-method", args->shadowMethod,
                     "hard (a ray to the light's centre), soft (SDF soft shadows, one march; RTSDF "
                     "§2.4-2.5), distributed (rays to points on the light: the ground truth), pcf "
                     "or evsm (shadow maps)")
        ->check(CLI::IsMember({"hard", "soft", "distributed", "pcf", "evsm"}));
    shading->add_option("--shadow-rays", args->shadowRays, "distributed: rays per point and light")
        ->check(CLI::Range(1, 65536));
    args->ao.option = shading->add_flag("--ao,!--no-ao", args->ao.value,
                                        "SDF ambient occlusion on the ambient term");
    shading
        ->add_option("--max-reflections", args->maxReflections,
                     "Whitted: mirror and Fresnel reflection bounces per ray (Keinert §4)")
        ->check(CLI::Range(0, 64));
    shading
        ->add_option("--max-refractions", args->maxRefractions,
                     "Whitted: refraction bounces per ray")
        ->check(CLI::Range(0, 64));
    shading
        ->add_option("--epsilon", args->epsilon,
                     "Secondary-ray origin offset: dynamic, 2 max(eps_min, |f(p)|) (Keinert "
                     "§3.3), or global (--global-epsilon along the normal)")
        ->check(CLI::IsMember({"dynamic", "global"}));
    shading->add_option("--global-epsilon", args->globalEpsilon, "The global offset")
        ->check(CLI::PositiveNumber);
    args->convexBounds.option = shading->add_flag(
        "--convex-bounds,!--no-convex-bounds", args->convexBounds.value,
        "Rays inside convex objects jump to the bounding box and trace back (Keinert §3.5)");

    auto* grid = cmd->add_option_group(
        "Grids", "Single-grid scenes, e.g. a .sdfg rendered directly (Jamriska 2010)");
    grid->add_option("--grid-tracer", args->gridTracer,
                     "dda: two-level 3D-DDA over blocks and cells (§4); sphere: sphere tracing")
        ->check(CLI::IsMember({"dda", "sphere"}));
    grid->add_option("--cell", args->cellMethod,
                     "Surface-cell intersection (§4.2): midpoint or false-position")
        ->check(CLI::IsMember({"midpoint", "false-position"}));
    grid->add_option("--cell-iterations", args->cellIterations, "False-position iterations (§4.2)")
        ->check(CLI::Range(1, 16));
    args->bitMasks.option =
        grid->add_flag("--bit-masks,!--no-bit-masks", args->bitMasks.value,
                       "Test per-block cell bit masks instead of 8 corner signs (§4.1)");
    grid->add_option("--grid-normals", args->gridNormals,
                     "Gradient estimator (§5): analytic, difference-of-interpolations, "
                     "interpolation-of-differences")
        ->check(CLI::IsMember(
            {"analytic", "difference-of-interpolations", "interpolation-of-differences"}));
    grid->add_option("--minmax", args->minMax,
                     "Min/max-buffer resolution for primary rays (§6), e.g. 64, 128, 256; 0 = off "
                     "(default 128)")
        ->check(CLI::Range(0, 4096));
    grid->add_option("--occluder", args->occluder,
                     "Shadow rays by volumetric occluders (§7) with restart threshold N; 0 = off")
        ->check(CLI::Range(0, 100000));

    auto* frames = cmd->add_option_group(
        "Frames", "Temporal accumulation of jittered frames (RTSDF §2.5.2; TAA after Karis 2014)");
    frames
        ->add_option("--frames", args->frames,
                     "Render N frames, each with a subpixel camera offset and new soft-shadow and "
                     "light-sample jitter, blended into the output (a running mean for stills)")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    frames
        ->add_option("--taa-alpha", args->taaAlpha,
                     "History weight of the blend in [0, 1) (default: running mean; 0.9 with "
                     "--orbit)")
        ->check(CLI::Range(0.0, 0.999999));
    frames
        ->add_option("--orbit", args->orbit,
                     "Animate: the camera orbits its target by this many degrees per frame; the "
                     "history is reprojected through depth and clamped to each frame's "
                     "neighbourhood")
        ->check(CLI::Range(-180.0, 180.0));
    frames->add_option("--frame-pattern", args->framePattern,
                       "Also write every accumulated frame, e.g. frames/out_%04d.png");
    cmd->add_option("--threads", args->threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, 1024));
    cmd->add_flag("-q,--quiet", args->quiet,
                  "No progress on stderr (the summary line is still printed)");
    cmd->callback([&action, args] { action = [args] { return runRender(*args); }; });
}

}  // namespace sdft::cli
