// sdftrace.Scene and sdftrace.render: scene files (and dicts, through their JSON text) with the
// CLI's validation and errors, rendered to numpy arrays with the tracer switches as keyword
// arguments (the render option table, scene/render_options.h).
#include <pybind11/stl.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "bindings.h"
#include "sdftrace/core/error.h"
#include "sdftrace/render/film.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/render/temporal.h"
#include "sdftrace/scene/grid_scene.h"
#include "sdftrace/scene/load_input.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"
#include "sdftrace/scene/prepare_scene.h"
#include "sdftrace/scene/render_options.h"

namespace sdft::py {

namespace {

PyScene loadScene(const pyb::handle& path, bool progress) {
    const std::string p = pathArgument(path);
    pyb::gil_scoped_release release;
    return PyScene{std::make_shared<const Scene>(loadSceneInput(p, progress).scene), p};
}

PyScene sceneFromText(const std::string& text, const std::string& source,
                      const std::string& baseDir) {
    pyb::gil_scoped_release release;
    Scene s = describeSceneText(text, source, baseDir);
    prepareScene(s);
    return PyScene{std::make_shared<const Scene>(std::move(s)), source};
}

Vec3 vec3Argument(const pyb::handle& value, const std::string& what) {
    std::vector<float> v;
    try {
        v = value.cast<std::vector<float>>();
    } catch (const pyb::cast_error&) {
        throw InputError(what + ": expected three numbers (x, y, z)");
    }
    if (v.size() != 3 || !std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
        throw InputError(what + ": expected three finite numbers (x, y, z)");
    return Vec3(v[0], v[1], v[2]);
}

std::string optionKeys() {
    std::string keys;
    for (const RenderOption& o : renderOptions())
        keys += (keys.empty() ? "" : ", ") + std::string(o.key);
    return keys;
}

// One tracer or shading switch by its scene-file key: bools take True/False, choices their word,
// numbers are range-checked by the option table.
void applyOption(RenderSettings& s, const std::string& key, const pyb::handle& value) {
    const RenderOption* o = findRenderOption(key);
    if (!o)
        throw InputError("render: " + key +
                         ": unknown keyword; accepted: scene, width, height, eye, target, up, "
                         "fov, aovs, frames, classic, threads, return_stats, and the render "
                         "options " +
                         optionKeys());
    const std::string shown = pyb::str(pyb::repr(value));
    const std::string where = "render: " + key + " = " + shown;
    double v = 0;
    if (o->type == OptionType::Bool) {
        if (!pyb::isinstance<pyb::bool_>(value))
            throw InputError(where + ": expected True or False");
        v = value.cast<bool>() ? 1 : 0;
    } else if (o->type == OptionType::Choice) {
        if (!pyb::isinstance<pyb::str>(value))
            throw InputError(where + ": expected one of " + o->choiceList());
        if (std::string e = o->parse(value.cast<std::string>(), v); !e.empty())
            throw InputError(where + ": " + e);
    } else {
        if (pyb::isinstance<pyb::bool_>(value) ||
            !(pyb::isinstance<pyb::int_>(value) || pyb::isinstance<pyb::float_>(value)))
            throw InputError(where + ": expected " + o->accepted());
        v = value.cast<double>();
        if (std::string e = o->check(v); !e.empty()) throw InputError(where + ": " + e);
    }
    o->give(s, v);
}

// The scene render() draws: a Scene, a Grid (framed automatically) or a path (as `render`).
std::shared_ptr<const Scene> sceneArgument(const pyb::handle& scene) {
    if (pyb::isinstance<PyScene>(scene)) return scene.cast<const PyScene&>().scene;
    if (pyb::isinstance<PyGrid>(scene)) {
        const auto& grid = scene.cast<const PyGrid&>().grid;
        const Bounds3 frame = grid->surfaceBounds();
        if (frame.empty()) throw InputError("render: scene: the grid contains no surface");
        return std::make_shared<const Scene>(sceneForObject(node::grid(grid), frame));
    }
    if (pyb::isinstance<pyb::str>(scene) || pyb::hasattr(scene, "__fspath__"))
        return loadScene(scene, false).scene;
    throw InputError("render: scene: expected an sdftrace.Scene, an sdftrace.Grid or a path");
}

pyb::dict statsDict(const RenderStats& st) {
    const double rays = std::max<double>(1, static_cast<double>(st.primaryRays));
    pyb::dict d;
    d["seconds"] = st.seconds;
    d["threads"] = st.threads;
    d["primary_rays"] = st.primaryRays;
    d["hits"] = st.hits;
    d["evaluations_per_ray"] = static_cast<double>(st.primaryEvaluations) / rays;
    d["evaluations_per_pixel"] = static_cast<double>(st.totalEvaluations()) / rays;
    d["shadow_rays"] = st.shadowRays;
    d["secondary_rays"] = st.secondaryRays;
    d["fallbacks"] = st.fallbacks;
    d["traversal_steps"] = st.traversalSteps;
    d["intersection_tests"] = st.intersectionTests;
    d["rays_per_second"] = static_cast<double>(st.primaryRays) / std::max(st.seconds, 1e-9);
    return d;
}

pyb::object render(const pyb::handle& sceneArg, std::optional<int> width, std::optional<int> height,
                   const pyb::handle& eye, const pyb::handle& target, const pyb::handle& up,
                   std::optional<float> fov, const std::vector<std::string>& aovs, int frames,
                   bool classic, std::optional<int> threads, bool returnStats,
                   const std::string& device, const pyb::kwargs& options) {
    const Device asked = deviceArgument(device, "render");
    Scene scene = *sceneArgument(sceneArg);
    CameraDesc& cam = scene.camera;
    if (!eye.is_none()) cam.eye = vec3Argument(eye, "render: eye");
    if (!target.is_none()) cam.target = vec3Argument(target, "render: target");
    if (!up.is_none()) cam.up = vec3Argument(up, "render: up");
    if (fov) {
        if (!(*fov > 0 && *fov < 180))
            throw InputError("render: fov = " + std::to_string(*fov) +
                             ": expected a vertical field of view in (0, 180) degrees");
        cam.fovDeg = *fov;
    }
    if (width) cam.width = *width;
    if (height) cam.height = *height;
    validateCamera(cam, "render: eye/target", "render: up", "render: width/height");
    if (frames < 1 || frames > 100000)
        throw InputError("render: frames = " + std::to_string(frames) +
                         ": expected an integer in [1, 100000]");
    if (threads && (*threads < 1 || *threads > 1024))
        throw InputError("render: threads: expected an integer in [1, 1024]");
    if (classic) scene.settings.trace = TraceOptions::classic();
    for (const auto& [key, value] : options) applyOption(scene.settings, pyb::str(key), value);
    if (threads) scene.settings.threads = *threads;
    unsigned kept = Film::bit(Aov::Color);
    std::vector<Aov> wanted;
    for (const std::string& name : aovs) {
        Aov aov;
        if (!parseAov(name, aov) || aov == Aov::Motion)
            throw InputError("render: aovs: '" + name +
                             "': expected names among color, depth, normal, steps, error, "
                             "trav_steps, isect_tests, shadow, ao");
        kept |= Film::bit(aov);
        wanted.push_back(aov);
    }
    RenderStats st;
    std::optional<Film> film;
    std::string fellBack;
    {
        pyb::gil_scoped_release release;
        const RenderPlan plan = planRender(scene);
        film.emplace(plan.camera.width, plan.camera.height, kept);
        const PlanRenderer renderer(plan, asked, "render: device = '" + device + "'");
        fellBack = renderer.why();
        if (frames == 1) {
            st = renderer.render(FrameView{plan.camera}, *film);
        } else {
            TemporalOptions t;
            t.frames = frames;
            st = renderFrames(plan, *film, t, nullptr, false, renderer.frames());
        }
    }
    if (asked == Device::Auto && !fellBack.empty()) warnCpuFallback("render", fellBack);
    pyb::dict images;
    for (Aov aov : wanted) {
        const std::vector<float>& data = film->channel(aov);
        const int c = aovChannels(aov);
        pyb::array_t<float> a(
            std::vector<pyb::ssize_t>{film->height, film->width, static_cast<pyb::ssize_t>(c)});
        std::copy(data.begin(), data.end(), a.mutable_data());
        images[aovName(aov)] = a;
    }
    if (returnStats) return pyb::make_tuple(images, statsDict(st));
    return images;
}

Field compileField(const PyScene& s, bool boundsCulling) {
    if (!s.scene->root) throw InputError(s.source + ": the scene has no objects");
    return Field{std::make_shared<const Tape>(
                     compileTape(s.scene->root, CompileOptions{.boundsCulling = boundsCulling})),
                 "field of " + s.source};
}

pyb::dict cameraDict(const CameraDesc& c) {
    pyb::dict d;
    d["eye"] = pyb::make_tuple(c.eye.x, c.eye.y, c.eye.z);
    d["target"] = pyb::make_tuple(c.target.x, c.target.y, c.target.z);
    d["up"] = pyb::make_tuple(c.up.x, c.up.y, c.up.z);
    d["fov"] = c.fovDeg;
    d["width"] = c.width;
    d["height"] = c.height;
    return d;
}

}  // namespace

void bindScene(pyb::module_& m) {
    pyb::class_<PyScene>(m, "Scene",
                         "A scene: analytic objects, grids and meshes with materials, lights and a "
                         "camera (docs/scene-format.md), its assets loaded and baked")
        .def_static("load", &loadScene, pyb::arg("path"), pyb::arg("progress") = false,
                    "Loads a scene file (.json), or a mesh or grid file framed automatically; "
                    "bad input raises ValueError naming the file and the JSON path.\n\n"
                    "path: the file (str or os.PathLike); its assets load relative to it.\n"
                    "progress: print each asset's loading and baking on stderr.")
        .def_static("_from_text", &sceneFromText, pyb::arg("text"), pyb::arg("source"),
                    pyb::arg("base_dir") = "")
        .def_static(
            "demo",
            [] {
                return PyScene{std::make_shared<const Scene>(demoScene()), "<demo>"};
            },
            "The built-in demo scene")
        .def_property_readonly(
            "field", [](const PyScene& s) { return compileField(s, false); },
            "The scene's whole field as a Field: the field's definition, Lipschitz-continuous "
            "(compile(bounds_culling=True) for the tracer's faster, culled bound)")
        .def("compile", &compileField, pyb::arg("bounds_culling") = false,
             "The scene's field compiled to a tape; bounds_culling=True skips union operands "
             "whose box is no nearer than the running minimum (decision 0002: a pointwise "
             "bound with the same zero set, faster, but not Lipschitz-continuous where the "
             "operands are bounds)")
        .def_property_readonly(
            "camera", [](const PyScene& s) { return cameraDict(s.scene->camera); },
            "The scene's camera: eye, target, up, fov, width, height")
        .def_property_readonly("source", [](const PyScene& s) { return s.source; })
        .def("__repr__", [](const PyScene& s) {
            return "<sdftrace.Scene: " + s.source + ", " +
                   std::to_string(s.scene->materials.size()) + " materials, " +
                   std::to_string(s.scene->lighting.lights.size()) + " lights>";
        });

    m.def("render", &render, pyb::arg("scene"), pyb::arg("width") = pyb::none(),
          pyb::arg("height") = pyb::none(), pyb::kw_only(), pyb::arg("eye") = pyb::none(),
          pyb::arg("target") = pyb::none(), pyb::arg("up") = pyb::none(),
          pyb::arg("fov") = pyb::none(), pyb::arg("aovs") = std::vector<std::string>{"color"},
          pyb::arg("frames") = 1, pyb::arg("classic") = false, pyb::arg("threads") = pyb::none(),
          pyb::arg("return_stats") = false, pyb::arg("device") = "cpu",
          "Ray traces a Scene, a Grid or a file to a dict of H x W x C float32 arrays, one per "
          "name in `aovs` (color: linear radiance; depth, normal, steps, error, trav_steps, "
          "isect_tests, shadow, ao). Keyword arguments set the render options by their scene "
          "keys (render_options()): omega=1.6, shadow_method='soft', ao=True, ... classic=True "
          "starts from plain sphere tracing. frames=N accumulates N jittered frames. "
          "return_stats=True returns (images, stats).\n\n"
          "scene: an sdftrace.Scene, an sdftrace.Grid (framed automatically) or a path to a "
          "scene, grid or mesh file.\n"
          "width, height: the image size in pixels (default: the scene camera's).\n"
          "eye, target, up: the camera's position, the point it looks at and its up vector, "
          "each (x, y, z) (default: the scene camera's).\n"
          "fov: the vertical field of view in degrees, in (0, 180).\n"
          "aovs: the outputs to return, by name.\n"
          "frames: jittered frames accumulated (temporal accumulation).\n"
          "classic: start from Hart's plain sphere tracing instead of the enhanced tracer.\n"
          "threads: worker threads (default: all cores).\n"
          "return_stats: also return the render's counters as a dict.\n"
          "device: where the frames render: 'cpu'; 'cuda' (the GPU, or ValueError saying why "
          "not: no CUDA backend in this build, no device, or what the GPU does not render); "
          "'auto' (the GPU where it can, else the CPU with a warning saying why). gpu_info() "
          "tells what GPU there is.");
    m.def(
        "render_options",
        [] {
            pyb::list out;
            for (const RenderOption& o : renderOptions()) {
                pyb::dict d;
                d["key"] = o.key;
                d["default"] = o.defaultText();
                d["accepted"] = o.accepted();
                d["doc"] = o.doc;
                d["group"] = o.group;
                out.append(d);
            }
            return out;
        },
        "Every render option render() takes as a keyword: key, default, accepted, doc, group");
}

}  // namespace sdft::py
