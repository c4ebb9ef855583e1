// sdftrace view [scene.json|field.sdfg|field.vdb|mesh.obj]: the interactive viewer
// (docs/viewer.md). The session (src/sdftrace/view) does the work; the window is in viewer/.
#include <cstdio>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include "commands.h"
#include "sdftrace/core/error.h"
#include "sdftrace/gpu/device.h"
#include "sdftrace/gpu/gpu_device.h"
#include "sdftrace/view/view_script.h"
#include "sdftrace/view/viewer_session.h"
#ifdef SDFT_HAVE_VIEWER
#include "viewer/viewer_window.h"
#endif

namespace sdft::cli {

namespace {

struct ViewArgs {
    std::string input;
    std::optional<int> width, height, threads;
    std::string eye, target, up;
    std::optional<float> fov;
    int frames = 8;
    int preview = 4;
    std::string script;
    std::string screenshotDir = ".";
    bool noPanel = false;
    std::string device = "cpu";
};

// view --device: each plan's passes on the chosen device (gpu/device.h). cuda without a GPU is
// one line before any window opens; auto falls back to the CPU and says why once.
std::function<FrameRenderFn(const RenderPlan&)> deviceRenderers(const std::string& name) {
    Device d = Device::Cpu;
    parseDevice(name, d);  // CLI11 checked the name
    if (d == Device::Cpu) return nullptr;
    if (d == Device::Cuda) requireGpu("--device cuda");
    auto noted = std::make_shared<bool>(false);
    return [d, name, noted](const RenderPlan& plan) -> FrameRenderFn {
        auto r = std::make_shared<PlanRenderer>(plan, d, "--device " + name);
        if (!r->gpu()) {
            if (!*noted)
                std::fprintf(stderr, "sdftrace view: --device auto: rendering on the CPU (%s)\n",
                             r->why().c_str());
            *noted = true;
            return nullptr;
        }
        return [r](const FrameView& view, Film& film, bool progress) {
            return r->render(view, film, progress);
        };
    };
}

std::string readScript(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError("--script " + path + ": cannot read the file");
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

int runView(const ViewArgs& a) {
    ViewerOptions o;
    o.input = a.input;
    o.width = a.width;
    o.height = a.height;
    auto vec = [](const std::string& flag, const std::string& text) {
        const Vec3Arg v = parseVec3Arg(flag, text);
        return Vec3(v.x, v.y, v.z);
    };
    if (!a.eye.empty()) o.eye = vec("--eye", a.eye);
    if (!a.target.empty()) o.target = vec("--target", a.target);
    if (!a.up.empty()) o.up = vec("--up", a.up);
    o.fov = a.fov;
    o.progressive.frames = a.frames;
    o.progressive.previewDivisor = a.preview;
    o.progressive.renderer = deviceRenderers(a.device);
    o.threads = a.threads.value_or(0);
    // The script and the input are checked before any window opens.
    std::vector<ViewCommand> script;
    if (!a.script.empty()) script = parseViewScript(readScript(a.script), a.script);
    ViewerSession session(o);
#ifdef SDFT_HAVE_VIEWER
    WindowOptions w;
    w.script = std::move(script);
    w.screenshotDir = a.screenshotDir;
    w.panel = !a.noPanel;
    return runViewerWindow(session, w);
#else
    throw InputError(
        "view: this build of sdftrace has no viewer (GLFW, OpenGL or Dear ImGui were not found "
        "when it was built: scripts/install-deps.sh installs libglfw3-dev and libimgui-dev)");
#endif
}

}  // namespace

void addViewCommand(CLI::App& app, Action& action) {
    auto args = std::make_shared<ViewArgs>();
    CLI::App* cmd = app.add_subcommand(
        "view",
        "Interactive viewer: orbit, pan, zoom and fly through a scene, switch the tracer, shading "
        "and AOV live; a preview while moving, refined when still (docs/viewer.md)");
    cmd->add_option("input", args->input,
                    "Scene file (JSON), grid file (.sdfg, .vdb) or mesh; default: the demo");
    cmd->add_option("--width", args->width, "Window and image width in pixels")
        ->check(CLI::Range(16, 16384));
    cmd->add_option("--height", args->height, "Window and image height in pixels")
        ->check(CLI::Range(16, 16384));
    cmd->add_option("--eye", args->eye, "Camera position x,y,z");
    cmd->add_option("--target", args->target, "Point looked at x,y,z");
    cmd->add_option("--up", args->up, "Up vector x,y,z");
    cmd->add_option("--fov", args->fov, "Vertical field of view in degrees")
        ->check(CLI::Range(1e-3, 179.999));
    cmd->add_option("--frames", args->frames,
                    "Jittered full-resolution frames accumulated once the view stops (as render "
                    "--frames)")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    cmd->add_option("--preview", args->preview,
                    "The preview while moving has 1/N of the width and height (1: none)")
        ->check(CLI::Range(1, 64))
        ->capture_default_str();
    cmd->add_option("--script", args->script,
                    "Drive the viewer from a file of commands (orbit, pan, zoom, fly, set, aov, "
                    "wait, screenshot, command, quit: docs/viewer.md)");
    cmd->add_option("--screenshot-dir", args->screenshotDir,
                    "Where F12 writes sdftrace-view-NNNN.png")
        ->capture_default_str();
    cmd->add_flag("--no-panel", args->noPanel, "Start with the panel hidden (Tab shows it)");
    cmd->add_option("--device", args->device,
                    "Where the passes render: cpu; cuda (the GPU, or one line saying why not); "
                    "auto (the GPU where it renders the scene, else the CPU, saying why)")
        ->check(CLI::IsMember({"cpu", "cuda", "auto"}))
        ->capture_default_str();
    cmd->add_option("--threads", args->threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, 1024));
    cmd->callback([&action, args] { action = [args] { return runView(*args); }; });
}

}  // namespace sdft::cli
