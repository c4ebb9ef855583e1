// sdftrace render [scene.json] -o image.png [--aov NAME=PATH]... [camera, tracer, shading flags]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include "commands.h"
#include "render_args.h"
#include "sdftrace/cluster/distributed_render.h"
#include "sdftrace/cluster/work_farm.h"
#include "sdftrace/core/error.h"
#include "sdftrace/core/frame_pattern.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/exec/progress.h"
#include "sdftrace/exec/thread_arena.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/gpu/gpu_device.h"
#include "sdftrace/io/atomic_file.h"
#include "sdftrace/io/grid_file.h"
#include "sdftrace/io/image_io.h"
#include "sdftrace/io/mesh_file.h"
#include "sdftrace/io/video_writer.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/render/temporal.h"
#include "sdftrace/scene/animated_scene.h"
#include "sdftrace/scene/load_input.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"
#include "sdftrace/scene/prepare_scene.h"
#include "sdftrace/scene/render_options.h"

namespace sdft::cli {

namespace {
Vec3 toVec3(const Vec3Arg& a) { return {a.x, a.y, a.z}; }
}  // namespace

void applyCamera(const RenderArgs& a, CameraDesc& cam) {
    if (!a.eye.empty()) cam.eye = toVec3(parseVec3Arg("--eye", a.eye));
    if (!a.target.empty()) cam.target = toVec3(parseVec3Arg("--target", a.target));
    if (!a.up.empty()) cam.up = toVec3(parseVec3Arg("--up", a.up));
    if (a.fov) cam.fovDeg = *a.fov;
    if (a.width) cam.width = *a.width;
    if (a.height) cam.height = *a.height;
    validateCamera(cam, "--eye/--target", "--up", "--width/--height");
}

// Flags override the scene's render block; --classic resets the tracer before them.
void applySettingOverrides(const RenderArgs& a, RenderSettings& s) {
    if (a.classic) s.trace = TraceOptions::classic();
    for (const OptionArg& arg : a.options) {
        if (!arg.given()) continue;
        double v = arg.value ? 1 : 0;
        if (arg.option->type != OptionType::Bool) {
            // Validated while parsing (addOptionFlags); parsed again here for the value.
            if (std::string error = arg.option->parse(arg.text, v); !error.empty())
                throw InputError(arg.option->mainFlag() + " " + arg.text + ": " + error);
        }
        arg.option->give(s, v);
    }
    if (a.threads) s.threads = *a.threads;
}

void applyOverrides(const RenderArgs& a, Scene& scene) {
    applyCamera(a, scene.camera);
    applySettingOverrides(a, scene.settings);
}

namespace {

void validateFramePattern(const std::string& pattern, const std::string& what = "--frame-pattern",
                          bool paths = true) {
    if (!isFramePattern(pattern)) {
        throw InputError(what + " " + pattern +
                         ": expected one frame-number field such as %d or %04d, e.g. out_%04d.png");
    }
    imageFormatFromPath(framePath(pattern, 0), what);
    if (paths) checkWritablePath(framePath(pattern, 0), what);
}

TimeSpan parseTimeArg(const std::string& text) {
    auto number = [&](const std::string& part) {
        char* end = nullptr;
        const double v = std::strtod(part.c_str(), &end);
        if (part.empty() || end != part.c_str() + part.size() || !std::isfinite(v) ||
            std::fabs(v) > 1e9)
            throw InputError("--time " + text +
                             ": expected a time T or a range A:B in seconds (numbers within "
                             "+-1e9), e.g. --time 1.5 or --time 0:4");
        return v;
    };
    TimeSpan span;
    const size_t colon = text.find(':');
    if (colon == std::string::npos) {
        span.from = span.to = number(text);
        return span;
    }
    span.range = true;
    span.from = number(text.substr(0, colon));
    span.to = number(text.substr(colon + 1));
    if (span.to < span.from)
        throw InputError("--time " + text + ": the range ends before it starts (expected A <= B)");
    return span;
}

}  // namespace

FrameTimes frameTimes(const TimeSpan& span, double fps, const std::string& timeText) {
    FrameTimes f;
    f.from = span.from;
    f.fps = fps;
    f.first = std::llround(span.from * fps);
    const double n = std::ceil((span.to - span.from) * fps - 1e-9);
    if (n > 1e6)
        throw InputError("--time " + timeText + ": " + std::to_string(static_cast<long long>(n)) +
                         " frames at " + std::to_string(fps) +
                         " fps; a range renders at most 1000000 frames");
    f.count = std::max(1LL, static_cast<long long>(n));
    return f;
}

namespace {

// Every output is validated before the (possibly long) render starts; the AOVs to write. A time
// range writes each frame through --frame-pattern and the --aov paths, each one a pattern.
// `paths`: whether the files can be written is checked too (under mpirun by rank 0 alone, which
// writes them; the other ranks need only the AOVs).
std::vector<std::pair<Aov, std::string>> validateOutputs(const RenderArgs& a, bool range,
                                                         bool paths = true) {
    if (range) {
        const bool video = a.outputFlag && a.outputFlag->count() > 0;
        if (video && !VideoWriter::isVideoPath(a.output))
            throw InputError("--output " + a.output +
                             ": a time range writes its frames through --frame-pattern (and "
                             "--aov NAME=PATTERN) or into a video: --output anim.mp4 (.mkv, .mov)");
        if (video && !VideoWriter::available())
            throw InputError("--output " + a.output +
                             ": this build of sdftrace writes no video (FFmpeg's libraries were "
                             "not found when it was built); write frames with --frame-pattern");
        if (video && paths) checkWritablePath(a.output, "--output");
        if (!video && a.framePattern.empty())
            throw InputError("--time " + a.time +
                             ": a time range renders one image per frame; give --frame-pattern, "
                             "e.g. --frame-pattern frames/%04d.png, or a video: -o anim.mp4");
        if (a.orbit != 0)
            throw InputError(
                "--orbit: cannot be combined with a --time range (keyframe the camera in the "
                "scene file instead; docs/scene-format.md, \"Animation\")");
        if (a.taa && a.frames > 1)
            throw InputError(
                "--taa: accumulates one jittered frame per instant across the "
                "range; it cannot be combined with --frames " +
                std::to_string(a.frames) + " (which accumulates at each instant)");
    } else {
        if (a.taa)
            throw InputError(
                "--taa: accumulates across the frames of a --time A:B range; for "
                "a still, use --frames N");
        imageFormatFromPath(a.output, "--output");
        if (paths) checkWritablePath(a.output, "--output");
    }
    if (!a.framePattern.empty()) validateFramePattern(a.framePattern, "--frame-pattern", paths);
    std::vector<std::pair<Aov, std::string>> aovs;
    for (const std::string& spec : a.aovs) {
        auto eq = spec.find('=');
        Aov aov;
        if (eq == std::string::npos || !parseAov(spec.substr(0, eq), aov) ||
            eq + 1 == spec.size()) {
            throw InputError(
                "--aov " + spec +
                ": expected NAME=PATH with NAME one of color, depth, normal, steps, error, "
                "trav_steps, isect_tests, shadow, ao, motion");
        }
        std::string path = spec.substr(eq + 1);
        if (range) {
            validateFramePattern(path, "--aov " + spec.substr(0, eq), paths);
        } else {
            imageFormatFromPath(path, "--aov " + spec.substr(0, eq));
            if (paths) checkWritablePath(path, "--aov " + spec.substr(0, eq));
        }
        aovs.emplace_back(aov, path);
    }
    return aovs;
}

}  // namespace

bool showProgress(const RenderArgs& a) {
    return !a.quiet && (stderrIsTerminal() || Communicator::world().distributed());
}

RenderStats renderImage(const RenderArgs& a, const RenderPlan& plan, Film& film,
                        const std::string& subFramePattern, bool progress,
                        const FrameRenderFn& across) {
    if (a.frames <= 1 && a.orbit == 0)
        return across ? across(FrameView{plan.camera}, film, progress)
                      : render(plan, film, progress);
    TemporalOptions t;
    t.frames = a.frames;
    t.orbitDegrees = a.orbit;
    if (a.taaAlpha) t.alpha = *a.taaAlpha;
    std::function<void(int, const Film&)> onFrame;
    if (!subFramePattern.empty()) {
        onFrame = [&](int k, const Film& f) {
            writeAov(f, Aov::Color, framePath(subFramePattern, k));
        };
    }
    return renderFrames(plan, film, t, onFrame, progress, across);
}

PrepareOptions prepareOptions(const RenderArgs& a, bool distributed, bool hostFields) {
    PrepareOptions o{.progress = !a.quiet && stderrIsTerminal(), .bakeMesh = {}};
    if (deviceOf(a) == Device::Cpu || distributed || !gpuInfo().present) return o;
    // With --device cuda the GPU renders every frame: RTSDF's per-frame grids stay on the device
    // (MeshBakeOptions::gpuResident). --device auto may fall back to the CPU, which needs them,
    // as do motion vectors.
    const bool resident = deviceOf(a) == Device::Cuda && !hostFields;
    o.bakeMesh = [resident](const TriangleMesh& mesh, const MeshBakeOptions& bake) {
        MeshBakeOptions b = bake;
        b.gpuResident = resident;
        // What the GPU bakes (jfa, rtsdf) it bakes; the rest the CPU.
        return bakeMeshOn(chooseBakeDevice(Device::Auto, bake, "").gpu, mesh, b);
    };
    return o;
}

Device deviceOf(const RenderArgs& a) {
    Device d = Device::Cpu;
    parseDevice(a.device, d);
    return d;
}

std::unique_ptr<PlanRenderer> deviceRenderer(const RenderArgs& a, const RenderPlan& plan,
                                             bool note) {
    const Device d = deviceOf(a);
    if (d == Device::Cpu) return nullptr;
    auto r = std::make_unique<PlanRenderer>(plan, d, "--device " + a.device);
    if (d == Device::Auto && !r->why().empty() && note && !a.quiet)
        std::fprintf(stderr, "sdftrace render: --device auto: rendering on the CPU (%s)\n",
                     r->why().c_str());
    return r->gpu() ? std::move(r) : nullptr;
}

namespace {

std::string threadsText(const RenderStats& st) {
    if (st.gpu) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "%s (GPU kernels %.3f ms, frames %.3f ms)",
                      gpuInfo().name.c_str(), st.gpuKernelMs, st.gpuFrameMs);
        return buf;
    }
    if (st.ranks <= 1) return std::to_string(st.threads) + " threads";
    return std::to_string(st.ranks) + " ranks (" + std::to_string(st.threads) + " threads)";
}

// The summary line on stderr (docs/cli.md "Outputs").
void printSummary(const RenderStats& st, const Film& film, const RenderPlan& plan) {
    const double rays = static_cast<double>(st.primaryRays);
    const float lipschitz = plan.tape.lipschitz();
    if (plan.settings.pathTracing) {
        const double rayCount =
            static_cast<double>(st.primaryRays + st.secondaryRays + st.shadowRays);
        std::fprintf(stderr,
                     "sdftrace render: %dx%d path traced, %.0f paths per pixel, in %.3f s on %s, "
                     "%.3f Mpaths/s, %.2f rays per path (%.2f shadow rays), %.2f "
                     "evaluations per path, L = %.3g\n",
                     film.width, film.height, rays / static_cast<double>(film.pixels()), st.seconds,
                     threadsText(st).c_str(), rays / st.seconds * 1e-6, rayCount / rays,
                     st.shadowRays / rays, st.totalEvaluations() / rays, lipschitz);
        return;
    }
    std::string counters;
    char buf[160];
    if (st.gridTracer) {
        std::snprintf(buf, sizeof buf,
                      ", DDA: %.2f traversal steps and %.2f intersection tests per pixel",
                      st.traversalSteps / rays, st.intersectionTests / rays);
        counters = buf;
    }
    if (st.secondaryRays) {
        std::snprintf(
            buf, sizeof buf, ", Whitted: %.2f secondary rays per pixel, %llu self-intersections",
            st.secondaryRays / rays, static_cast<unsigned long long>(st.selfIntersections));
        counters += buf;
    }
    std::fprintf(stderr,
                 "sdftrace render: %dx%d in %.3f s on %s, %.3f Mrays/s, %.2f evaluations per "
                 "primary ray (%.2f per pixel with normals and shadows), %.2f%% hits, %llu "
                 "over-relaxation fallbacks, L = %.3g%s\n",
                 film.width, film.height, st.seconds, threadsText(st).c_str(),
                 rays / st.seconds * 1e-6, st.primaryEvaluations / rays,
                 st.totalEvaluations() / rays, 100.0 * st.hits / rays,
                 static_cast<unsigned long long>(st.fallbacks), lipschitz, counters.c_str());
}

}  // namespace

AnimatedScene loadAnimation(const std::string& input) {
    return input.empty() ? AnimatedScene::fromText(demoSceneText(), "<demo scene>")
                         : AnimatedScene::fromFile(input);
}

Scene previousInstant(const AnimatedScene& anim, const RenderArgs& a, double t, double fps) {
    Scene before = anim.describeAt(t - 1.0 / fps);
    applyCamera(a, before.camera);
    return before;
}

MotionVectors frameMotion(const RenderArgs& a, const Film& film, const FrameView& view,
                          const Scene& before, const Scene& now) {
    const SceneMotion motion(before.root, now.root);
    return motionVectors(film.depth, view.camera, view.pixelJitter, before.camera,
                         a.taaMotion == "objects" ? &motion : nullptr);
}

namespace {

// A still's scene: the input (a scene, grid or mesh file, or the demo), or a scene file's instant
// --time T (with its animation, for the motion AOV).
struct StillScene {
    Scene scene;
    std::optional<AnimatedScene> anim;
};

StillScene loadStill(const RenderArgs& a, const std::optional<TimeSpan>& span, bool distributed) {
    StillScene still;
    if (span) {
        still.anim.emplace(loadAnimation(a.scene));
        AssetCache cache;
        still.scene = still.anim->at(span->from, cache, prepareOptions(a, distributed));
    } else {
        // A mesh or grid file's grid gets its gap lattice only if the render reads it.
        RenderSettings settings;
        applySettingOverrides(a, settings);
        LoadedInput input = loadSceneInput(a.scene, !a.quiet && stderrIsTerminal(),
                                           prepareOptions(a, distributed).bakeMesh,
                                           loneGridReadsDistances(settings));
        if (!a.quiet && !input.note.empty())
            std::fprintf(stderr, "sdftrace render: %s\n", input.note.c_str());
        still.scene = std::move(input.scene);
    }
    applyOverrides(a, still.scene);
    return still;
}

// The still on this process, or (rank 0 of an mpirun job) its tiles across the ranks.
RenderStats renderStill(const RenderArgs& a, const RenderPlan& plan, Film& film,
                        Communicator& comm) {
    const std::unique_ptr<PlanRenderer> gpu = deviceRenderer(a, plan, true);
    if (!comm.distributed())
        return renderImage(a, plan, film, a.framePattern, showProgress(a),
                           gpu ? gpu->frames() : nullptr);
    // A GPU renders a frame faster than its tiles would travel: rank 0's renders the still and
    // the other ranks wait (an animation's frames are dealt to every rank's GPU).
    WorkFarm farm(comm);
    const RenderStats st =
        gpu ? renderImage(a, plan, film, a.framePattern, showProgress(a), gpu->frames())
            : renderImage(a, plan, film, a.framePattern, showProgress(a),
                          [&](const FrameView& view, Film& f, bool progress) {
                              return renderAcross(farm, plan, view, f, progress);
                          });
    farm.end();
    return st;
}

int runRender(const RenderArgs& args) {
    if (args.listOptions) {
        std::fputs(renderOptionsMarkdown().c_str(), stdout);
        return 0;
    }
    Communicator& comm = Communicator::world();
    RenderArgs a = args;
    if (comm.distributed()) {
        if (!a.threads) a.threads = defaultRankThreads(comm);
        if (!comm.root()) a.quiet = true;  // progress and notes from rank 0 only
    }
    std::optional<TimeSpan> span;
    std::vector<std::pair<Aov, std::string>> aovs;
    together(comm, [&] {
        span = a.time.empty() ? std::nullopt : std::optional<TimeSpan>(parseTimeArg(a.time));
        if (span && (isMeshFile(a.scene) || isGridFile(a.scene)))
            throw InputError("--time " + a.time + ": " + a.scene +
                             " is not a scene file; only scene files have keyframes "
                             "(docs/scene-format.md, \"Animation\")");
        aovs = validateOutputs(a, span && span->range, comm.root());  // rank 0 writes them
        // Before loading anything: under mpirun one GPU per rank (the machine's GPUs in turn),
        // and cuda needs one on every rank.
        if (deviceOf(a) != Device::Cpu && comm.distributed()) useGpuOfLocalRank(comm.localRank());
        if (deviceOf(a) == Device::Cuda) requireGpu("--device cuda");
    });
    if (span && span->range) return renderAnimation(a, *span, aovs, comm);
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    StillScene still;
    std::optional<RenderPlan> planned;
    auto t1 = t0;
    together(comm, [&] {
        still = loadStill(a, span, comm.distributed());
        t1 = Clock::now();
        planned.emplace(planRender(still.scene));
    });
    const RenderPlan& plan = *planned;
    if (comm.distributed() && !comm.root()) {
        serveRounds(comm, [&](const Bytes& c) {
            ByteReader in(c);
            return tileWorker(plan, in);
        });
        return 0;
    }
    const double instant = span ? span->from : 0.0;
    unsigned kept = Film::bit(Aov::Color);  // the film keeps only the AOVs to be written
    for (const auto& [aov, path] : aovs) kept |= Film::bit(aov);
    if (kept & Film::bit(Aov::Motion)) kept |= Film::bit(Aov::Depth);
    Film film(plan.camera.width, plan.camera.height, kept);
    const auto t2 = Clock::now();
    const RenderStats st = renderStill(a, plan, film, comm);
    if (still.anim && film.has(Aov::Motion)) {  // --time T: the motion from T - 1/fps
        const double fps = a.fps ? *a.fps : still.anim->time().fps;
        film.motion = frameMotion(a, film, FrameView{plan.camera},
                                  previousInstant(*still.anim, a, instant, fps), still.scene)
                          .motion;
    }
    const auto t3 = Clock::now();
    writeAov(film, Aov::Color, a.output);
    for (const auto& [aov, path] : aovs) writeAov(film, aov, path);
    const auto t4 = Clock::now();
    printSummary(st, film, plan);
    if (!a.quiet) {
        auto s = [](Clock::time_point x, Clock::time_point y) {
            return std::chrono::duration<double>(y - x).count();
        };
        std::fprintf(stderr,
                     "sdftrace render: phases: load %.3f s, plan %.3f s, render %.3f s, write "
                     "%.3f s\n",
                     s(t0, t1), s(t1, t2), s(t2, t3), s(t3, t4));
    }
    return 0;
}

}  // namespace

namespace {

// One flag per row of the option table, grouped as the table groups them; values are checked by the
// table while parsing, so a bad one is reported as CLI11 reports any bad flag.
void addOptionFlags(CLI::App* cmd, RenderArgs& args) {
    std::map<std::string, CLI::Option_group*> groups;
    const auto options = renderOptions();
    args.options.resize(options.size());  // fixed from here on: CLI11 keeps pointers into it
    for (size_t i = 0; i < options.size(); ++i) {
        const RenderOption& o = options[i];
        OptionArg& arg = args.options[i];
        arg.option = &o;
        CLI::Option_group*& group = groups[o.group];
        if (!group) group = cmd->add_option_group(o.group);
        const std::string help = std::string(o.doc) + " [" + o.defaultText() + "]";
        if (o.type == OptionType::Bool) {
            const std::string names = o.mainFlag() + ",!--no-" + o.mainFlag().substr(2);
            arg.cli = group->add_flag(names, arg.value, help);
            continue;
        }
        CLI::Validator valid(
            [&o](std::string& text) {
                double v = 0;
                return o.parse(text, v);
            },
            o.type == OptionType::Choice ? o.choiceList() : o.accepted());
        const char* type = o.type == OptionType::Choice ? "NAME"
                           : o.type == OptionType::Int  ? "INT"
                                                        : "FLOAT";
        arg.cli = group->add_option(o.flags, arg.text, help)->type_name(type)->check(valid);
    }
}

void addCameraFlags(CLI::App* cmd, RenderArgs& args) {
    auto* camera = cmd->add_option_group("Camera", "Override the scene's camera");
    camera->add_option("--eye", args.eye, "Camera position x,y,z");
    camera->add_option("--target", args.target, "Point looked at x,y,z");
    camera->add_option("--up", args.up, "Up vector x,y,z");
    camera->add_option("--fov", args.fov, "Vertical field of view in degrees, in (0, 180)")
        ->check(CLI::Range(1e-3, 179.999));
    camera->add_option("--width", args.width, "Image width in pixels")->check(CLI::Range(1, 65536));
    camera->add_option("--height", args.height, "Image height in pixels")
        ->check(CLI::Range(1, 65536));
}

void addFrameFlags(CLI::App* cmd, RenderArgs& args) {
    auto* frames = cmd->add_option_group(
        "Frames", "Temporal accumulation of jittered frames (RTSDF §2.5.2; TAA after Karis 2014)");
    frames
        ->add_option("--frames", args.frames,
                     "Render N frames, each with a subpixel camera offset and new soft-shadow and "
                     "light-sample jitter, blended into the output (a running mean for stills)")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    frames
        ->add_option("--taa-alpha", args.taaAlpha,
                     "History weight of the blend in [0, 1) (default: running mean; 0.9 with "
                     "--orbit)")
        ->check(CLI::Range(0.0, 0.999999));
    frames
        ->add_option("--orbit", args.orbit,
                     "Animate: the camera orbits its target by this many degrees per frame; the "
                     "history is reprojected through depth and clamped to each frame's "
                     "neighbourhood")
        ->check(CLI::Range(-180.0, 180.0));
    frames->add_flag("--taa", args.taa,
                     "With a --time range: temporal anti-aliasing across its frames, one "
                     "jittered frame per instant blended into a history reprojected by each "
                     "pixel's motion (the camera's and each object's), rejected where the "
                     "previous frame saw another object or depth, clamped to the neighbourhood "
                     "(alpha: --taa-alpha, default 0.9)");
    frames
        ->add_option("--taa-motion", args.taaMotion,
                     "What --taa reprojects by: objects (the camera and each object's keyframed "
                     "placement) or camera (the camera only, the --orbit method)")
        ->check(CLI::IsMember({"objects", "camera"}))
        ->capture_default_str();
    frames->add_option("--frame-pattern", args.framePattern,
                       "Also write every accumulated frame, e.g. frames/out_%04d.png; with a "
                       "--time range, the animation's frames");
    auto* anim = cmd->add_option_group(
        "Animation", "Scenes with keyframed values (docs/scene-format.md, \"Animation\")");
    anim->add_option("--time", args.time,
                     "Render the instant T (seconds), or the frames of the range A:B at --fps "
                     "(t = A, A + 1/fps, ... while t < B; written through --frame-pattern and "
                     "--aov NAME=PATTERN, frame numbers counted from round(A fps), and/or into "
                     "an H.264 video with -o anim.mp4, .mkv or .mov)")
        ->type_name("T|A:B");
    anim->add_option("--fps", args.fps,
                     "Frames per second of a --time range (default: the scene's \"animation\" "
                     "block, else 30)")
        ->check(CLI::Range(1e-3, 1000.0));
}

}  // namespace

void addRenderCommand(CLI::App& app, Action& action) {
    auto args = std::make_shared<RenderArgs>();
    CLI::App* cmd = app.add_subcommand(
        "render",
        "Ray trace a scene file (or the built-in demo scene when none is given) to an image");
    cmd->add_option("scene", args->scene,
                    "Scene file (JSON, see docs/scene-format.md), grid file (.sdfg, .vdb) or mesh, "
                    "framed automatically; default: the demo");
    args->outputFlag = cmd->add_option("-o,--output", args->output,
                                       "Output image: .png (tone-mapped sRGB), .exr or .pfm "
                                       "(linear); with a --time range, a video: .mp4, .mkv, "
                                       ".mov (H.264)")
                           ->capture_default_str();
    cmd->add_option(
        "--aov", args->aovs,
        "Extra output NAME=PATH, repeatable. NAME: color (linear radiance), depth (t along the "
        "unit primary ray, inf on a miss), normal, steps (field evaluations of the primary "
        "ray), error (f where the march placed the hit, before the root refinement), trav_steps "
        "and isect_tests (grid DDA), shadow (the "
        "first shadowing light's visibility), ao (ambient occlusion), motion (with --time: pixels "
        "to where the surface was one frame earlier). PATH: .exr, .pfm, or .png (heat map with "
        "legend)");
    addCameraFlags(cmd, *args);
    cmd->add_flag("--classic", args->classic,
                  "Plain sphere tracing (Hart): no over-relaxation (fixed or adaptive), no "
                  "screen-space selection, no "
                  "discontinuity reduction; the option flags still apply after it");
    addOptionFlags(cmd, *args);
    addFrameFlags(cmd, *args);
    cmd->add_option("--threads", args->threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, 1024));
    cmd->add_option(
           "--device", args->device,
           "Where the frames render: cpu; cuda (the GPU: direct lighting with hard, "
           "soft or distributed shadows and AO, plastic materials, mirrors and glass by "
           "Whitted rays, the path tracer, any field: analytic, CSG, blends, grids and "
           "baked meshes in a scene; an error names what only the CPU renders yet: "
           "triangle primaries, textures, shadow maps); auto (the GPU where one is present "
           "and renders the scene, else the CPU). With a GPU, meshes baked by jfa or "
           "rtsdf (dynamic rtsdf meshes every frame) bake on it too")
        ->check(CLI::IsMember({"cpu", "cuda", "auto"}))
        ->capture_default_str();
    cmd->add_flag("-q,--quiet", args->quiet,
                  "No progress on stderr (the summary line is still printed)");
    cmd->add_flag("--list-options", args->listOptions,
                  "Print every render option (scene key, flag, default, accepted values) as a "
                  "Markdown table and exit");
    cmd->callback([&action, args] { action = [args] { return runRender(*args); }; });
}

}  // namespace sdft::cli
