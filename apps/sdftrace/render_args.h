// What `sdftrace render` was given and the parts of the render that its still and animation paths
// share (render_command.cpp); --time ranges render in render_animation.cpp.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "commands.h"
#include "sdftrace/cluster/communicator.h"
#include "sdftrace/gpu/device.h"
#include "sdftrace/render/film.h"
#include "sdftrace/render/motion.h"
#include "sdftrace/render/render_plan.h"
#include "sdftrace/render/render_stats.h"
#include "sdftrace/render/temporal.h"
#include "sdftrace/scene/animated_scene.h"
#include "sdftrace/scene/render_options.h"
#include "sdftrace/scene/scene.h"

namespace sdft::cli {

// A render option given on the command line: its row of the option table and what was given.
struct OptionArg {
    const RenderOption* option = nullptr;
    std::string text;    // non-bool options: the value as written
    bool value = false;  // bool options: --x or --no-x
    CLI::Option* cli = nullptr;
    bool given() const { return cli && cli->count() > 0; }
};

struct RenderArgs {
    std::string scene;
    std::string output = "render.png";
    std::vector<std::string> aovs;
    std::string eye, target, up;
    std::optional<float> fov;
    std::optional<int> width, height, threads;
    bool classic = false;
    std::vector<OptionArg> options;  // one per row of renderOptions(), in its order
    int frames = 1;
    std::optional<float> taaAlpha;
    float orbit = 0;
    bool taa = false;                   // --taa: accumulate across a --time range's frames
    std::string taaMotion = "objects";  // --taa-motion objects|camera
    std::string framePattern;
    std::string time;           // --time T or A:B (scene files with keyframes)
    std::optional<double> fps;  // --fps (default: the scene's)
    CLI::Option* outputFlag = nullptr;
    bool quiet = false;
    bool listOptions = false;
    std::string device = "cpu";  // --device cpu|cuda|auto
};

// --time: one instant T, or the frames of [A, B) at --fps (docs/cli.md, "Animation").
struct TimeSpan {
    double from = 0, to = 0;
    bool range = false;  // A:B
};

// The frames of a range: t_i = A + i / fps while t_i < B (one frame when A = B), numbered from
// round(A fps) so that a range's frames keep their numbers on the whole timeline.
struct FrameTimes {
    long long first = 0;  // the number of frame 0
    long long count = 1;
    double from = 0, fps = 30;
    double at(long long i) const { return from + static_cast<double>(i) / fps; }
};

FrameTimes frameTimes(const TimeSpan& span, double fps, const std::string& timeText);

// The flags' camera (validated) and render options over the scene's.
void applyCamera(const RenderArgs& a, CameraDesc& cam);
void applySettingOverrides(const RenderArgs& a, RenderSettings& settings);
void applyOverrides(const RenderArgs& a, Scene& scene);

// Whether progress is shown: on a terminal, and on a distributed job's rank 0 whatever its stderr
// (a pipe to mpirun: progress lines, exec/progress.h).
bool showProgress(const RenderArgs& a);

// One frame, or temporally accumulated frames (--frames, --orbit). `across`, when set, renders each
// frame on every rank of the job (mpirun).
RenderStats renderImage(const RenderArgs& a, const RenderPlan& plan, Film& film,
                        const std::string& subFramePattern, bool progress,
                        const FrameRenderFn& across = nullptr);

// --device: the GPU renderer of `plan` (null: the CPU renders it). cuda: the GPU or one clear
// error; auto: the GPU where one is present and renders the plan, else the CPU, saying why on
// stderr when `note`. Under mpirun each rank's own GPU (useGpuOfLocalRank). The library's choice
// (gpu/device.h) with the CLI's note.
std::unique_ptr<PlanRenderer> deviceRenderer(const RenderArgs& a, const RenderPlan& plan,
                                             bool note);
// How the scene's meshes bake under --device (prepare_scene.h): cuda, or auto with a GPU present,
// bake on the GPU what it bakes (jfa and rtsdf: RTSDF's per-frame regeneration of dynamic meshes),
// the rest on the CPU; cpu, mpirun or no GPU: empty (bakeMesh on the CPU). Under cuda, RTSDF's
// per-frame grids stay on the device (MeshBakeOptions::gpuResident) unless `hostFields`: motion
// vectors evaluate the objects' fields on the host (SceneMotion::objectAt).
PrepareOptions prepareOptions(const RenderArgs& a, bool distributed, bool hostFields = false);
// The --device flag as the library's Device (CLI11 checked the name).
Device deviceOf(const RenderArgs& a);

// The scene of --time: a scene file, or the demo.
AnimatedScene loadAnimation(const std::string& input);
// The instant one frame before t, described (its assets pending: only its camera and placements
// are read), with the flags' camera: where motion vectors point.
Scene previousInstant(const AnimatedScene& anim, const RenderArgs& a, double t, double fps);
// The motion AOV and the reprojection of --taa: per-pixel motion to the previous instant, from
// the camera and, unless --taa-motion camera, each object's placement.
MotionVectors frameMotion(const RenderArgs& a, const Film& film, const FrameView& view,
                          const Scene& before, const Scene& now);

// --time A:B: the frames rendered (across the job's ranks under mpirun) and written through the
// patterns and/or the video, a line per frame and a total.
int renderAnimation(const RenderArgs& a, const TimeSpan& span,
                    const std::vector<std::pair<Aov, std::string>>& aovs, Communicator& comm);

}  // namespace sdft::cli
