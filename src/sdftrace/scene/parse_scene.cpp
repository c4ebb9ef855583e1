#include "sdftrace/scene/parse_scene.h"

#include <unistd.h>

#include <cmath>
#include <map>

#include "json_reader.h"
#include "parse_node.h"
#include "parse_texture.h"
#include "scene_json.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/render/film.h"
#include "sdftrace/scene/animated_scene.h"
#include "sdftrace/scene/prepare_scene.h"
#include "sdftrace/scene/render_options.h"

namespace sdft {

using json_reader::Json;
using json_reader::nonNegative;
using json_reader::positive;
using json_reader::Reader;

extern const char* const kDemoSceneJson;  // generated from examples/demo.json

namespace {

constexpr int kMaxImageSide = 65536;

void parseCamera(const Reader& r, CameraDesc& cam) {
    r.requireObject("the camera");
    r.allowKeys({"eye", "target", "up", "fov", "width", "height"});
    cam.eye = r.vec3("eye", cam.eye);
    cam.target = r.vec3("target", cam.target);
    cam.up = r.vec3("up", cam.up);
    cam.fovDeg = r.number(
        "fov", cam.fovDeg, [](double v) { return v > 0 && v < 180; },
        "a vertical field of view in degrees in (0, 180)");
    cam.width = r.integer("width", cam.width, 1, kMaxImageSide);
    cam.height = r.integer("height", cam.height, 1, kMaxImageSide);
    if (length(cam.target - cam.eye) <= 0) r.failKey("target", "must differ from the eye");
    if (length(cross(normalize(cam.target - cam.eye), cam.up)) < 1e-6f) {
        r.failKey("up", "must not be parallel to the viewing direction");
    }
}

Material parseMaterial(const Reader& r, const std::string& name, Scene& scene,
                       TextureContext& textures) {
    r.requireObject("a material");
    r.allowKeys(
        {"type", "color", "diffuse", "specular", "shininess", "roughness", "ior", "absorption"});
    Material m;
    m.name = name;
    const std::string type = r.string("type", "plastic");
    if (type == "plastic") {
        m.kind = Material::Kind::Plastic;
    } else if (type == "mirror") {
        m.kind = Material::Kind::Mirror;
        m.color = Vec3(0.95f);
    } else if (type == "dielectric") {
        m.kind = Material::Kind::Dielectric;
    } else {
        r.failKey("type",
                  "unknown material type '" + type + "'; accepted: plastic, mirror, dielectric");
    }
    m.ior = r.number(
        "ior", m.ior, [](double v) { return v >= 1 && v <= 10; },
        "an index of refraction in [1, 10]");
    m.absorption = r.vec3("absorption", m.absorption, nonNegative,
                          "non-negative absorption coefficients per unit length");
    m.colorTexture = parseColorInput(r, "color", m.color, scene, textures);
    m.diffuse = r.number("diffuse", m.diffuse, nonNegative, "a non-negative weight");
    m.specular = r.number("specular", m.specular, nonNegative, "a non-negative weight");
    m.shininess = r.number(
        "shininess", m.shininess, [](double v) { return v >= 1 && v <= 1e5; },
        "a Blinn-Phong exponent in [1, 100000]");
    if (r.has("roughness"))
        m.roughness = r.number(
            "roughness", 0.5f, [](double v) { return v >= 0 && v <= 1; },
            "a GGX roughness (alpha) in [0, 1]");
    return m;
}

Light parseLight(const Reader& r) {
    r.requireObject("a light");
    Light l;
    std::string type = r.string("type");
    if (type == "directional") {
        r.allowKeys({"type", "direction", "angle", "color", "intensity", "shadows"});
        l.kind = Light::Kind::Directional;
        l.direction = r.vec3("direction");
        if (length(l.direction) <= 0) r.failKey("direction", "expected a non-zero direction");
        l.direction = normalize(l.direction);
        l.angle = radians(r.number(
            "angle", 0.0f, [](double v) { return v >= 0 && v < 90; },
            "an angular diameter in [0, 90) degrees"));
    } else if (type == "point") {
        r.allowKeys({"type", "position", "color", "intensity", "shadows"});
        l.kind = Light::Kind::Point;
        l.position = r.vec3("position");
    } else if (type == "sphere") {
        r.allowKeys({"type", "position", "radius", "color", "intensity", "shadows"});
        l.kind = Light::Kind::Sphere;
        l.position = r.vec3("position");
        l.radius = r.number("radius", positive, "a positive radius (use a point light for 0)");
    } else if (type == "rect") {
        r.allowKeys({"type", "position", "u", "v", "color", "intensity", "shadows"});
        l.kind = Light::Kind::Rect;
        l.position = r.vec3("position");
        l.u = r.vec3("u");
        l.v = r.vec3("v");
        if (!(length(cross(l.u, l.v)) > 1e-12f * std::max(1.0f, dot(l.u, l.u) + dot(l.v, l.v))))
            r.failKey("v", "expected edge vectors u and v spanning a non-zero area");
    } else {
        r.failKey("type",
                  "unknown light type '" + type + "'; accepted: directional, point, sphere, rect");
    }
    l.color = r.vec3("color", l.color, nonNegative, "non-negative linear RGB");
    l.intensity = r.number("intensity", l.intensity, nonNegative, "a non-negative intensity");
    l.castShadows = r.boolean("shadows", true);
    return l;
}

// The render block: one key per row of the option table (render_options.h).
void parseRender(const Reader& r, RenderSettings& s) {
    r.requireObject("render settings");
    std::vector<std::string> keys;
    for (const RenderOption& o : renderOptions()) keys.push_back(o.key);
    r.allowKeys(keys);
    for (const RenderOption& o : renderOptions()) {
        if (!r.has(o.key)) continue;
        const double v = json_reader::optionValue(r, o.key, o.value());
        o.give(s, v);
    }
}

// The "animation" block: {"start": s, "end": e, "fps": f}, every key optional (defaults from `t`;
// the end no earlier than the start).
SceneTime parseAnimation(const Reader& r, SceneTime t) {
    r.requireObject("an animation block {\"start\": s, \"end\": e, \"fps\": f}");
    r.allowKeys({"start", "end", "fps"});
    t.start = r.number("start", static_cast<float>(t.start), json_reader::anyFinite,
                       "a start time in seconds");
    t.end = r.number("end", static_cast<float>(std::max(t.end, t.start)), json_reader::anyFinite,
                     "an end time in seconds");
    if (t.end < t.start)
        r.failKey("end", "the end time " + json_reader::show(t.end) + " is before the start time " +
                             json_reader::show(t.start));
    t.fps = r.number(
        "fps", static_cast<float>(t.fps), [](double v) { return v > 0 && v <= 1000; },
        "frames per second in (0, 1000]");
    return t;
}

Scene parseRoot(const Json& root, const std::string& source, const std::string& baseDir,
                double time) {
    Reader r(root, source, "");
    r.requireObject("a scene");
    r.allowKeys({"camera", "lights", "ambient", "background", "environment", "textures",
                 "materials", "objects", "render", "animation"});
    Scene scene;
    scene.materials.push_back(Material{"default"});
    NodeContext context;
    context.baseDir = baseDir;
    context.scene = &scene;
    context.time = time;
    std::map<std::string, int>& materialIndex = context.materials;
    materialIndex["default"] = 0;
    TextureContext textures;
    textures.baseDir = baseDir;
    if (r.has("textures")) {
        Reader t = r.child("textures");
        t.requireObject("a map from texture names to textures");
        for (auto it = t.value().begin(); it != t.value().end(); ++it)
            textures.named[it.key()] = parseTexture(t.child(it.key()), it.key(), scene, textures);
    }
    if (r.has("materials")) {
        Reader m = r.child("materials");
        m.requireObject("a map from material names to materials");
        for (auto it = m.value().begin(); it != m.value().end(); ++it) {
            int index = static_cast<int>(scene.materials.size());
            if (it.key() == "default") index = 0;
            Material mat = parseMaterial(m.child(it.key()), it.key(), scene, textures);
            if (index == 0)
                scene.materials[0] = mat;
            else
                scene.materials.push_back(mat);
            materialIndex[it.key()] = index;
        }
    }
    if (r.has("camera")) parseCamera(r.child("camera"), scene.camera);
    if (r.has("lights")) {
        Reader l = r.child("lights");
        l.requireArray("a list of lights");
        for (size_t i = 0; i < l.value().size(); ++i)
            scene.lighting.lights.push_back(parseLight(l.element(i)));
    }
    scene.lighting.ambient =
        r.vec3("ambient", scene.lighting.ambient, nonNegative, "non-negative linear RGB");
    scene.lighting.background =
        r.vec3("background", scene.lighting.background, nonNegative, "non-negative linear RGB");
    scene.lighting.environment =
        r.vec3("environment", scene.lighting.environment, nonNegative, "non-negative linear RGB");
    if (r.has("render")) parseRender(r.child("render"), scene.settings);
    if (!r.has("objects")) r.fail("missing required key 'objects' (a list of at least one object)");
    Reader objs = r.child("objects");
    objs.requireArray("a list of objects");
    if (objs.value().empty()) objs.fail("expected at least one object");
    std::vector<NodePtr> nodes;
    for (size_t i = 0; i < objs.value().size(); ++i)
        nodes.push_back(parseNode(objs.element(i), context));
    scene.root = nodes.size() == 1 ? nodes[0] : node::unite(nodes);
    // Objects smaller than float geometry resolves (their grids are checked when prepared).
    const Bounds3 b = nodeBounds(*scene.root);
    if (b.finite() && !b.empty() && maxComponent(b.extent()) < 1e-6f) {
        char buf[160];
        std::snprintf(buf, sizeof buf,
                      "the objects span only %.3g; scenes need at least 1e-6 across (scale them "
                      "up)",
                      maxComponent(b.extent()));
        objs.fail(buf);
    }
    validateImageSize(scene.camera.width, scene.camera.height, source + ": /camera");
    return scene;
}

}  // namespace

Json readSceneJson(const std::string& text, const std::string& source) {
    try {
        return Json::parse(text);
    } catch (const Json::exception& e) {
        // nlohmann's message reads "[json.exception.parse_error.101] parse error at line 3, ...";
        // an overflowing number ("1e999") is an out_of_range error of the parser.
        std::string msg = e.what();
        auto pos = msg.find("] ");
        msg = pos == std::string::npos ? msg : msg.substr(pos + 2);
        if (e.id == 406) msg += " (numbers must be finite)";
        throw InputError(source + ": malformed JSON: " + msg);
    }
}

SceneTime sceneTimeOf(const Json& root, const std::vector<JsonTrack>& tracks,
                      const std::string& source) {
    SceneTime t;
    t.animated = !tracks.empty();
    if (!tracks.empty()) {
        t.start = tracks.front().track.firstTime();
        t.end = tracks.front().track.lastTime();
        for (const JsonTrack& track : tracks) {
            t.start = std::min(t.start, track.track.firstTime());
            t.end = std::max(t.end, track.track.lastTime());
        }
    }
    Reader r(root, source, "");
    if (r.has("animation")) {  // its defaults: start 0, end the keys' end, 30 fps
        SceneTime defaults;
        defaults.end = t.end;
        defaults.animated = t.animated;
        t = parseAnimation(r.child("animation"), defaults);
    }
    return t;
}

Scene describeSceneJson(const Json& root, const std::string& source, const std::string& baseDir,
                        double time) {
    return parseRoot(root, source, baseDir, time);
}

void validateCamera(const CameraDesc& c, const std::string& eyeTarget, const std::string& up,
                    const std::string& size) {
    if (length(c.target - c.eye) <= 0)
        throw InputError(eyeTarget + ": the eye must differ from the target");
    if (length(cross(normalize(c.target - c.eye), c.up)) < 1e-6f)
        throw InputError(up + ": must not be parallel to the viewing direction");
    validateImageSize(c.width, c.height, size);
}

void validateImageSize(int width, int height, const std::string& what) {
    if (width < 1 || height < 1 || width > kMaxImageSide || height > kMaxImageSide) {
        throw InputError(what + ": image size " + std::to_string(width) + "x" +
                         std::to_string(height) +
                         " is out of range; width and height must be in [1, " +
                         std::to_string(kMaxImageSide) + "]");
    }
    checkMemoryBudget(Film::bytesNeeded(width, height), what,
                      "the film of a " + std::to_string(width) + "x" + std::to_string(height) +
                          " image with its AOVs",
                      "render a smaller image");
}

Scene describeSceneText(const std::string& text, const std::string& source,
                        const std::string& baseDir) {
    // A scene with keyframed values is checked at every key and described at its start.
    const AnimatedScene scene = AnimatedScene::fromText(text, source, baseDir);
    return scene.describeAt(scene.time().start);
}

Scene describeSceneFile(const std::string& path) {
    const AnimatedScene scene = AnimatedScene::fromFile(path);
    return scene.describeAt(scene.time().start);
}

Scene parseSceneText(const std::string& text, const std::string& source,
                     const std::string& baseDir) {
    Scene scene = describeSceneText(text, source, baseDir);
    prepareScene(scene);
    return scene;
}

Scene parseSceneFile(const std::string& path) {
    Scene scene = describeSceneFile(path);
    prepareScene(scene);
    return scene;
}

const char* demoSceneText() { return kDemoSceneJson; }

Scene demoScene() { return parseSceneText(kDemoSceneJson, "<demo scene>", ""); }

}  // namespace sdft
