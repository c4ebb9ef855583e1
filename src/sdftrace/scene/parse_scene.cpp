#include "sdftrace/scene/parse_scene.h"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "json_reader.h"
#include "parse_node.h"
#include "parse_texture.h"
#include "sdftrace/render/film.h"
#include "sdftrace/scene/option_names.h"

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
        l.angle = r.number(
                      "angle", 0.0f, [](double v) { return v >= 0 && v < 90; },
                      "an angular diameter in [0, 90) degrees") *
                  3.14159265f / 180.0f;
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

void parseRender(const Reader& r, RenderSettings& s) {
    r.requireObject("render settings");
    r.allowKeys({"max_steps",
                 "tau",
                 "omega",
                 "screen_space",
                 "force_hit",
                 "discontinuity_iterations",
                 "fixed_steps",
                 "hybrid",
                 "hybrid_epsilon",
                 "hybrid_step",
                 "falsi_iterations",
                 "normals",
                 "shadows",
                 "max_distance",
                 "shadow_offset",
                 "bounds_culling",
                 "grid_tracer",
                 "cell_intersection",
                 "cell_iterations",
                 "bit_masks",
                 "grid_normals",
                 "occluder_threshold",
                 "minmax_resolution",
                 "shadow_method",
                 "shadow_rays",
                 "soft_max_step",
                 "soft_bias",
                 "soft_triangulation",
                 "soft_jitter",
                 "soft_centered",
                 "shadow_map_resolution",
                 "pcf_radius",
                 "evsm_radius",
                 "ao",
                 "ao_samples",
                 "ao_step",
                 "ao_strength",
                 "max_reflections",
                 "max_refractions",
                 "secondary_epsilon",
                 "global_epsilon",
                 "convex_bounds",
                 "integrator",
                 "spp",
                 "max_depth"});
    TraceOptions& t = s.trace;
    t.maxSteps = r.integer("max_steps", t.maxSteps, 1, 100000);
    t.tau = r.number("tau", t.tau, positive, "a positive hit threshold");
    t.omega = r.number(
        "omega", t.omega, [](double v) { return v >= 1 && v < 2; },
        "an over-relaxation factor in [1, 2)");
    t.screenSpace = r.boolean("screen_space", t.screenSpace);
    t.forceHit = r.boolean("force_hit", t.forceHit);
    t.discontinuityIters = r.integer("discontinuity_iterations", t.discontinuityIters, 0, 64);
    t.fixedSteps = r.boolean("fixed_steps", t.fixedSteps);
    t.hybrid = r.boolean("hybrid", t.hybrid);
    t.hybridEpsilon = r.number("hybrid_epsilon", t.hybridEpsilon, positive, "a positive distance");
    t.hybridStep = r.number("hybrid_step", t.hybridStep, positive, "a positive step length");
    t.falsiIters = r.integer("falsi_iterations", t.falsiIters, 0, 64);
    std::string normals = r.string("normals", "tetrahedral");
    if (normals == "central")
        s.normals = NormalEstimator::Central;
    else if (normals == "tetrahedral")
        s.normals = NormalEstimator::Tetrahedral;
    else
        r.failKey("normals", "unknown estimator '" + normals + "'; accepted: central, tetrahedral");
    s.shadows = r.boolean("shadows", s.shadows);
    s.boundsCulling = r.boolean("bounds_culling", s.boundsCulling);
    // Jamriška 2010: single-grid scenes.
    auto named = [&](const char* key, auto parse, const char* names, auto& out) {
        if (!r.has(key)) return;
        std::string v = r.string(key);
        if (!parse(v, out)) r.failKey(key, "unknown value '" + v + "'; accepted: " + names);
    };
    named("grid_tracer", parseGridTracer, gridTracerNames(), s.gridTracer);
    named("cell_intersection", parseCellIntersection, cellIntersectionNames(),
          s.gridTrace.cellMethod);
    named("grid_normals", parseGridNormal, gridNormalNames(), s.gridNormals);
    s.gridTrace.falsiIters = r.integer("cell_iterations", s.gridTrace.falsiIters, 1, 16);
    s.gridTrace.bitMasks = r.boolean("bit_masks", s.gridTrace.bitMasks);
    s.occluderThreshold = r.integer("occluder_threshold", s.occluderThreshold, 0, 100000);
    s.minMaxResolution = r.integer("minmax_resolution", s.minMaxResolution, 0, 4096);
    s.maxDistance = r.number("max_distance", s.maxDistance, positive, "a positive distance");
    s.shadowOffsetMin =
        r.number("shadow_offset", s.shadowOffsetMin, positive, "a positive distance");
    // Soft shadows, distributed shadows, shadow maps and ambient occlusion.
    named("shadow_method", parseShadowMethod, shadowMethodNames(), s.shadowMethod);
    s.shadowRays = r.integer("shadow_rays", s.shadowRays, 1, 65536);
    const auto nonNegativeLength = [](double v) { return v >= 0 && v < 1e30; };
    s.soft.maxStep = r.number("soft_max_step", s.soft.maxStep, nonNegativeLength,
                              "a non-negative distance (0: unlimited)");
    s.soft.bias = r.number("soft_bias", s.soft.bias, nonNegativeLength, "a non-negative distance");
    s.soft.triangulate = r.boolean("soft_triangulation", s.soft.triangulate);
    s.soft.jitter = r.boolean("soft_jitter", s.soft.jitter);
    s.soft.centered = r.boolean("soft_centered", s.soft.centered);
    s.shadowMap.resolution = r.integer("shadow_map_resolution", s.shadowMap.resolution, 16, 8192);
    s.shadowMap.pcfRadius = r.integer("pcf_radius", s.shadowMap.pcfRadius, 0, 64);
    s.shadowMap.evsmRadius = r.integer("evsm_radius", s.shadowMap.evsmRadius, 0, 64);
    s.ambientOcclusion = r.boolean("ao", s.ambientOcclusion);
    s.ao.samples = r.integer("ao_samples", s.ao.samples, 1, 64);
    s.ao.step = r.number("ao_step", s.ao.step, positive, "a positive distance");
    s.ao.strength =
        r.number("ao_strength", s.ao.strength, nonNegativeLength, "a non-negative weight");
    // Whitted rays (Keinert §4) and their origin offset (§3.3).
    s.maxReflections = r.integer("max_reflections", s.maxReflections, 0, 64);
    s.maxRefractions = r.integer("max_refractions", s.maxRefractions, 0, 64);
    const std::string eps = r.string("secondary_epsilon", s.dynamicEpsilon ? "dynamic" : "global");
    if (eps != "dynamic" && eps != "global")
        r.failKey("secondary_epsilon", "unknown offset '" + eps + "'; accepted: dynamic, global");
    s.dynamicEpsilon = eps == "dynamic";
    s.globalEpsilon = r.number("global_epsilon", s.globalEpsilon, positive, "a positive distance");
    s.convexBounds = r.boolean("convex_bounds", s.convexBounds);
    // The integrator: direct lighting or the path tracer.
    const std::string integrator = r.string("integrator", s.pathTracing ? "path" : "direct");
    if (integrator != "direct" && integrator != "path")
        r.failKey("integrator", "unknown integrator '" + integrator + "'; accepted: direct, path");
    s.pathTracing = integrator == "path";
    s.samplesPerPixel = r.integer("spp", s.samplesPerPixel, 1, 1 << 20);
    s.maxDepth = r.integer("max_depth", s.maxDepth, 1, 1024);
}

Scene parseRoot(const Json& root, const std::string& source, const std::string& baseDir) {
    Reader r(root, source, "");
    r.requireObject("a scene");
    r.allowKeys({"camera", "lights", "ambient", "background", "environment", "textures",
                 "materials", "objects", "render"});
    Scene scene;
    scene.materials.push_back(Material{"default"});
    NodeContext context;
    context.baseDir = baseDir;
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
    validateImageSize(scene.camera.width, scene.camera.height, source + ": /camera");
    return scene;
}

}  // namespace

void validateImageSize(int width, int height, const std::string& what) {
    if (width < 1 || height < 1 || width > kMaxImageSide || height > kMaxImageSide) {
        throw InputError(what + ": image size " + std::to_string(width) + "x" +
                         std::to_string(height) +
                         " is out of range; width and height must be in [1, " +
                         std::to_string(kMaxImageSide) + "]");
    }
    double need = Film::bytesNeeded(width, height);
    double have = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * sysconf(_SC_PAGE_SIZE);
    if (need > 0.5 * have) {
        char buf[256];
        std::snprintf(
            buf, sizeof buf,
            "image %dx%d needs %.1f GiB of film, more than half of this machine's %.1f GiB; "
            "render a smaller image",
            width, height, need / (1 << 30), have / (1 << 30));
        throw InputError(what + ": " + buf);
    }
}

Scene parseSceneText(const std::string& text, const std::string& source,
                     const std::string& baseDir) {
    Json root;
    try {
        root = Json::parse(text);
    } catch (const Json::exception& e) {
        // nlohmann's message reads "[json.exception.parse_error.101] parse error at line 3, ...";
        // an overflowing number ("1e999") is an out_of_range error of the parser.
        std::string msg = e.what();
        auto pos = msg.find("] ");
        msg = pos == std::string::npos ? msg : msg.substr(pos + 2);
        if (e.id == 406) msg += " (numbers must be finite)";
        throw InputError(source + ": malformed JSON: " + msg);
    }
    return parseRoot(root, source, baseDir);
}

Scene parseSceneFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw InputError(path + ": cannot open scene file (does it exist and is it readable?)");
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw InputError(path + ": cannot read scene file");
    return parseSceneText(text.str(), path, std::filesystem::path(path).parent_path().string());
}

const char* demoSceneText() { return kDemoSceneJson; }

Scene demoScene() { return parseSceneText(kDemoSceneJson, "<demo scene>", ""); }

}  // namespace sdft
