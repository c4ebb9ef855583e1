#include "parse_node.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "sdftrace/bake/bake_options.h"
#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/bake/texture_coords.h"
#include "sdftrace/core/frame_pattern.h"
#include "sdftrace/field/noise.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/io/grid_file.h"
#include "sdftrace/io/mesh_file.h"

namespace sdft {

using json_reader::nonNegative;
using json_reader::positive;
using json_reader::Reader;

namespace {

std::vector<NodePtr> parseChildren(const Reader& r, NodeContext& mats, size_t minCount,
                                   size_t maxCount) {
    if (!r.has("children")) r.fail("missing required key 'children' (an array of objects)");
    Reader list = r.child("children");
    list.requireArray("a list of child objects");
    size_t n = list.value().size();
    if (n < minCount || n > maxCount) {
        std::string want = minCount == maxCount ? "exactly " + std::to_string(minCount)
                                                : "at least " + std::to_string(minCount);
        list.fail("expected " + want + " children, got " + std::to_string(n));
    }
    std::vector<NodePtr> out;
    for (size_t i = 0; i < n; ++i) out.push_back(parseNode(list.element(i), mats));
    return out;
}

NodePtr parseSingleChild(const Reader& r, NodeContext& mats) {
    if (!r.has("child")) r.fail("missing required key 'child' (an object)");
    return parseNode(r.child("child"), mats);
}

Mat3 parseRotation(const Reader& r, const std::string& key) {
    const auto& v = r.value().at(key);
    if (v.is_object()) {
        Reader rot = r.child(key);
        rot.allowKeys({"axis", "angle"});
        Vec3 axis = rot.vec3("axis");
        if (length(axis) <= 0) rot.failKey("axis", "expected a non-zero axis");
        float angle = rot.number("angle", json_reader::anyFinite, "an angle in degrees");
        return rotationAxisAngle(axis, angle);
    }
    if (!v.is_array()) {
        r.failKey(key,
                  "expected {\"axis\": [x,y,z], \"angle\": degrees} or [x, y, z] Euler degrees");
    }
    // Euler angles in degrees, applied about X, then Y, then Z.
    Vec3 e = r.vec3(key, nullptr, "Euler angles in degrees");
    Mat3 rx = rotationAxisAngle({1, 0, 0}, e.x), ry = rotationAxisAngle({0, 1, 0}, e.y),
         rz = rotationAxisAngle({0, 0, 1}, e.z);
    auto mul = [](const Mat3& a, const Mat3& b) {
        Mat3 c;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                c.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
        return c;
    };
    return mul(rz, mul(ry, rx));
}

Vec3 parseScale(const Reader& r, const std::string& key) {
    const auto& v = r.value().at(key);
    if (v.is_number()) {
        float s = r.number(key, positive, "a positive number or 3 positive numbers");
        return Vec3(s);
    }
    return r.vec3(key, positive, "positive scale factors");
}

// Applies the optional inline transform keys of any object: scale, then rotate, then translate.
NodePtr applyInlineTransforms(const Reader& r, NodePtr n) {
    if (r.has("scale")) n = node::scale(n, parseScale(r, "scale"));
    if (r.has("rotate")) n = node::rotate(n, parseRotation(r, "rotate"));
    if (r.has("translate")) n = node::translate(n, r.vec3("translate"));
    return n;
}

// A path from the scene file, relative to its directory unless absolute.
std::filesystem::path resolvePath(const NodeContext& ctx, const std::string& file) {
    std::filesystem::path path(file);
    if (path.is_relative() && !ctx.baseDir.empty())
        path = std::filesystem::path(ctx.baseDir) / path;
    return path;
}

// The index of `request` among the scene's asset requests; an identical earlier one is reused.
int addRequest(NodeContext& ctx, AssetRequest request) {
    if (!request.key.empty()) {
        auto it = ctx.requestIndex.find(request.key);
        if (it != ctx.requestIndex.end()) return it->second;
    }
    const int index = static_cast<int>(ctx.scene->assets.size());
    if (!request.key.empty()) ctx.requestIndex[request.key] = index;
    ctx.scene->assets.push_back(std::move(request));
    return index;
}

// A grid file, relative to the scene file's directory: loaded by prepareScene.
NodePtr requestGridFile(const Reader& r, NodeContext& ctx, const char* jsonKey = "file") {
    const std::string file = r.string(jsonKey);
    const std::string path = resolvePath(ctx, file).lexically_normal().string();
    if (!isGridFile(path))
        r.failKey(jsonKey, "unsupported grid file '" + file + "'; accepted: .sdfg, .vdb");
    AssetRequest q;
    q.kind = AssetRequest::Kind::GridFile;
    q.where = r.location(jsonKey);
    q.path = path;
    q.key = "grid|" + path;
    return node::gridAsset(addRequest(ctx, std::move(q)));
}

// A mesh object's file: "mesh", or for a mesh sequence (issue 16) the file of the frame number
// "frame" (keyframed to play it) in the pattern "mesh".
std::string meshFileOf(const Reader& r) {
    const std::string file = r.string("mesh");
    const bool pattern = file.find('%') != std::string::npos;
    if (!r.has("frame") && !pattern) return file;
    if (!r.has("frame"))
        r.failKey("mesh", "'" + file +
                              "' is a file pattern; give \"frame\" (a frame number, "
                              "keyframed to play the sequence) or name one file");
    const double frame = r.number(
        "frame", [](double v) { return v >= 0; }, "a frame number >= 0 (floored)");
    if (!isFramePattern(file))
        r.failKey("mesh", "'" + file +
                              "': a mesh sequence's file pattern holds one frame-number field "
                              "such as %d or %04d, e.g. frames/mesh_%04d.obj");
    return framePath(file, static_cast<long long>(std::floor(frame)));
}

// A mesh object's "dynamic" block (issue 16): regenerated every frame, "rebake" afresh by its
// bake method (the reference), "rtsdf" by RTSDF's per-frame pipeline with temporal accumulation
// (Tan et al. 2022, §2.5.1). `method` is the object's static bake method.
void parseDynamic(const Reader& r, const std::string& method, AssetRequest& q) {
    Reader d = r.child("dynamic");
    d.requireObject("a dynamic block {\"method\": \"rtsdf\" | \"rebake\", ...}");
    d.allowKeys({"method", "rays", "alpha", "mask"});
    const std::string how = d.string("method");
    if (how == "rtsdf") {
        if (r.has("method") && method != "rtsdf")
            r.failKey("method",
                      "a mesh with \"dynamic\": {\"method\": \"rtsdf\"} is "
                      "baked by rtsdf every frame; drop \"method\" or use rebake");
        q.dynamic = AssetRequest::Dynamic::Rtsdf;
        q.bake.method = MeshBakeMethod::Rtsdf;
        q.bake.rtsdf.rays = d.integer("rays", 1, 1, 4096);
        q.alpha = d.number(
            "alpha", 0.95f, [](double v) { return v >= 0 && v < 1; }, "a decay factor in [0, 1)");
        q.bake.rtsdf.maskVoxels = d.number(
            "mask", 3.0f, [](double v) { return v > 0 && v <= 64; },
            "a mask distance in (0, 64] fine voxels");
    } else if (how == "rebake") {
        for (const char* k : {"rays", "alpha", "mask"})
            if (d.has(k)) d.failKey(k, "applies to \"method\": \"rtsdf\" only");
        q.dynamic = AssetRequest::Dynamic::Rebake;
    } else {
        d.failKey("method", "unknown dynamic method '" + how + "'; accepted: rtsdf, rebake");
    }
    q.key.clear();  // never served from the cache: baked again every frame
}

// A mesh object's "play" block (issue 16): the file's own skeletal or morph animation, posed at
// start + speed * (the scene's time) seconds into a clip; each pose is a mesh of its own.
void parsePlay(const Reader& r, const NodeContext& ctx, AssetRequest& q) {
    Reader p = r.child("play");
    p.requireObject("a play block {\"animation\": index or name, \"speed\", \"start\", \"loop\"}");
    p.allowKeys({"animation", "speed", "start", "loop"});
    if (r.has("frame"))
        r.failKey("play", "a mesh sequence (\"frame\") cannot also play an animation; use one");
    AssetRequest::Play play;
    play.where = r.location("play");
    if (p.has("animation") && p.child("animation").value().is_string())
        play.clip = p.string("animation");
    else
        play.clipIndex = p.integer("animation", 0, 0, 1 << 20);
    const float speed = p.number("speed", 1.0f, json_reader::anyFinite, "a playback rate");
    const float start =
        p.number("start", 0.0f, json_reader::anyFinite, "a clip time in seconds at scene time 0");
    play.seconds = static_cast<double>(start) + static_cast<double>(speed) * ctx.time;
    play.loop = p.boolean("loop", true);
    char pose[64];
    std::snprintf(pose, sizeof pose, "|play|%d|%.9g|%d", play.clipIndex, play.seconds, play.loop);
    q.key += pose + play.clip;
    q.play = std::move(play);
}

// The bake option table's keys (bake/bake_options.h) an object gives; `mesh`: the mesh-only ones
// too. The others keep the table's defaults.
MeshBakeOptions readBakeOptions(const Reader& r, bool mesh) {
    MeshBakeOptions o;
    for (const BakeOption& option : bakeOptions()) {
        if (!r.has(option.key) || (option.meshOnly && !mesh)) continue;
        const double v = json_reader::optionValue(r, option.key, option.value());
        option.set(o, v);
    }
    return o;
}

// The keys of the bake option table an object takes (`mesh`: all, else those of every bake).
std::vector<const char*> bakeOptionKeys(bool mesh) {
    std::vector<const char*> keys;
    for (const BakeOption& option : bakeOptions())
        if (mesh || !option.meshOnly) keys.push_back(option.key);
    return keys;
}

// A mesh file (relative to the scene file) baked by prepareScene (a sparse grid unless "dense");
// the same file with the same options is baked once.
NodePtr requestMesh(const Reader& r, NodeContext& ctx) {
    const std::string file = meshFileOf(r);
    const std::string path = resolvePath(ctx, file).lexically_normal().string();
    if (r.has("play") ? !isAnimatedMeshFile(path) : !isMeshFile(path)) {
        r.failKey("mesh", "unsupported mesh file '" + file +
                              (r.has("play") ? "' to play; accepted: .gltf, .glb, .dae, .fbx, .x"
                                             : "'; accepted: .obj, .ply, .stl, .off, .gltf, .glb"));
    }
    const MeshBakeOptions bake = readBakeOptions(r, true);
    try {
        validateMeshBakeOptions(bake);
    } catch (const InputError& e) {
        r.failKey("sign", e.what());
    }
    AssetRequest q;
    q.kind = AssetRequest::Kind::Mesh;
    q.where = r.location("mesh");
    q.path = path;
    q.bake = bake;
    q.key = "mesh|" + path + "|" + bakeOptionsKey(bake);
    if (r.has("play")) parsePlay(r, ctx, q);
    if (r.has("dynamic")) parseDynamic(r, meshBakeMethodName(bake.method), q);
    return node::gridAsset(addRequest(ctx, std::move(q)));
}

// {"type": "bake", "child": {...}}: the child's field sampled into a sparse grid by prepareScene,
// optionally with projected texture coordinates (Liktor 2008, §5.5.2).
NodePtr requestSubtree(const Reader& r, NodeContext& ctx) {
    AssetRequest q;
    q.kind = AssetRequest::Kind::Subtree;
    q.where = r.location("child");
    q.subtree = parseSingleChild(r, ctx);
    // Checked here when the child is analytic, else once its grids are loaded.
    if (!hasPendingAssets(*q.subtree) && !boundedField(q.subtree)) r.failKey("child", kUnbounded);
    q.sampling = readBakeOptions(r, false).sampling;
    if (r.has("texcoords")) {
        TexcoordOptions t;
        const std::string helper = r.string("texcoords");
        if (!parseTexcoordKind(helper, t.helper))
            r.failKey("texcoords", "unknown helper '" + helper + "'; accepted: sphere, cylinder");
        t.axis = r.vec3("texcoord_axis", t.axis);
        if (!(length(t.axis) > 0)) r.failKey("texcoord_axis", "expected a non-zero vector");
        if (r.has("texcoord_center")) {
            t.center = r.vec3("texcoord_center");
            t.autoCenter = false;
        }
        q.texcoords = t;
    } else if (r.has("texcoord_axis") || r.has("texcoord_center")) {
        r.fail("texcoord_axis and texcoord_center need \"texcoords\": \"sphere\" or \"cylinder\"");
    }
    return node::gridAsset(addRequest(ctx, std::move(q)));
}

// The keys every object may carry: inline transforms, then the material.
// The material goes on the object inside its transforms, so that its textures see the object's
// own frame (texture.h); the transforms pass it on unchanged.
NodePtr finishNode(const Reader& r, NodePtr n, const NodeContext& mats) {
    if (r.has("material")) {
        std::string name = r.string("material");
        auto it = mats.materials.find(name);
        if (it == mats.materials.end()) {
            std::string known;
            for (const auto& [k, v] : mats.materials) known += (known.empty() ? "" : ", ") + k;
            r.failKey("material", "unknown material '" + name + "'; defined: " + known);
        }
        n = node::withMaterial(n, it->second);
    }
    return applyInlineTransforms(r, n);
}

// Operators and transforms (Liktor 2008, §2.2; Keinert et al. 2014), one function each.
NodePtr parseUnionOrIntersection(const Reader& r, NodeContext& ctx, const std::string& type) {
    allowObjectKeys(r, type, {"children"});
    auto c = parseChildren(r, ctx, 1, 100000);
    return type == "union" ? node::unite(c) : node::intersect(c);
}

// a minus the union of the others.
NodePtr parseDifference(const Reader& r, NodeContext& ctx, const std::string& type) {
    allowObjectKeys(r, type, {"children"});
    auto c = parseChildren(r, ctx, 2, 100000);
    NodePtr cutters = c.size() == 2 ? c[1] : node::unite({c.begin() + 1, c.end()});
    return node::subtract(c[0], cutters);
}

NodePtr parseComplement(const Reader& r, NodeContext& ctx, const std::string& type) {
    allowObjectKeys(r, type, {"child"});
    return node::complement(parseSingleChild(r, ctx));
}

NodePtr parseSmooth(const Reader& r, NodeContext& ctx, const std::string& type) {
    allowObjectKeys(r, type, {"children", "k"});
    const float k = r.number("k", nonNegative, "a non-negative blend radius");
    auto c = parseChildren(r, ctx, 2, 100000);
    if (type == "smooth_difference") {
        NodePtr cutters = c.size() == 2 ? c[1] : node::unite({c.begin() + 1, c.end()});
        return node::smoothDifference(c[0], cutters, k);
    }
    NodePtr n = c[0];
    for (size_t i = 1; i < c.size(); ++i)
        n = type == "smooth_union" ? node::smoothUnion(n, c[i], k)
                                   : node::smoothIntersection(n, c[i], k);
    return n;
}

NodePtr parseMorph(const Reader& r, NodeContext& ctx, const std::string& type) {
    allowObjectKeys(r, type, {"children", "weight"});
    const float w = r.number(
        "weight", [](double v) { return v >= 0 && v <= 1; }, "a weight in [0, 1]");
    auto c = parseChildren(r, ctx, 2, 2);
    return node::morph(c[0], c[1], w);
}

NodePtr parseTranslate(const Reader& r, NodeContext& ctx, const std::string& type) {
    allowObjectKeys(r, type, {"child", "offset"});
    return node::translate(parseSingleChild(r, ctx), r.vec3("offset"));
}

NodePtr parseRotate(const Reader& r, NodeContext& ctx, const std::string& type) {
    allowObjectKeys(r, type, {"child", "axis", "angle"});
    const Vec3 axis = r.vec3("axis");
    if (length(axis) <= 0) r.failKey("axis", "expected a non-zero axis");
    const float angle = r.number("angle", json_reader::anyFinite, "an angle in degrees");
    return node::rotate(parseSingleChild(r, ctx), rotationAxisAngle(axis, angle));
}

NodePtr parseScaleNode(const Reader& r, NodeContext& ctx, const std::string& type) {
    allowObjectKeys(r, type, {"child", "factors"});
    if (!r.has("factors")) r.fail("missing required key 'factors' (a number or 3 numbers)");
    return node::scale(parseSingleChild(r, ctx), parseScale(r, "factors"));
}

// Copies must not overlap: the repetition's distance bound assumes each cell holds one copy.
NodePtr parseRepeat(const Reader& r, NodeContext& ctx, const std::string& type) {
    allowObjectKeys(r, type, {"child", "cell", "count"});
    const Vec3 cell = r.vec3("cell", positive, "positive cell sizes");
    const Vec3 count = r.vec3(
        "count", [](double v) { return v >= 0 && v <= 1000 && v == std::floor(v); },
        "whole numbers of copies per side in [0, 1000]");
    NodePtr child = parseSingleChild(r, ctx);
    if (hasPendingAssets(*child)) {  // checked once its grids are loaded (prepareScene)
        ctx.scene->repeatChecks.push_back({child, cell, count, r.source() + ": " + r.path()});
    } else if (std::string error = repeatOverlap(nodeBounds(*child), cell, count); !error.empty()) {
        r.failKey("cell", error);
    }
    return node::repeat(child, cell, count);
}

NodePtr parseDisplace(const Reader& r, NodeContext& ctx, const std::string& type) {
    allowObjectKeys(r, type, {"child", "amplitude", "frequency", "octaves", "gain"});
    const float amplitude = r.number("amplitude", nonNegative, "a non-negative amplitude");
    const float frequency = r.number("frequency", 1.0f, positive, "a positive frequency");
    const int octaves = r.integer("octaves", 3, 1, 12);
    const float gain = r.number(
        "gain", 0.5f, [](double v) { return v > 0 && v < 1; }, "a gain in (0, 1)");
    return node::displace(parseSingleChild(r, ctx), amplitude, frequency, octaves, gain);
}

NodePtr parseGridNode(const Reader& r, NodeContext& ctx, const std::string& type) {
    allowObjectKeys(r, type, {"file"});
    return requestGridFile(r, ctx);
}

NodePtr parseBake(const Reader& r, NodeContext& ctx, const std::string& type) {
    std::vector<const char*> keys = {"child", "texcoords", "texcoord_axis", "texcoord_center"};
    for (const char* k : bakeOptionKeys(false)) keys.push_back(k);
    allowObjectKeys(r, type, keys);
    return requestSubtree(r, ctx);
}

struct OperatorParser {
    const char* name;
    NodePtr (*parse)(const Reader&, NodeContext&, const std::string&);
};

constexpr OperatorParser kOperators[] = {
    {"union", parseUnionOrIntersection},
    {"intersection", parseUnionOrIntersection},
    {"difference", parseDifference},
    {"complement", parseComplement},
    {"smooth_union", parseSmooth},
    {"smooth_intersection", parseSmooth},
    {"smooth_difference", parseSmooth},
    {"morph", parseMorph},
    {"translate", parseTranslate},
    {"rotate", parseRotate},
    {"scale", parseScaleNode},
    {"repeat", parseRepeat},
    {"displace", parseDisplace},
    {"grid", parseGridNode},
    {"bake", parseBake},
};

std::string objectTypeNames() {
    std::string names = primitiveTypeNames();
    for (const OperatorParser& o : kOperators)
        if (std::string(o.name) != "grid") names += std::string(", ") + o.name;
    return names;
}

}  // namespace

bool boundedField(const NodePtr& n) {
    const Bounds3 b = compileTape(n, {.boundsCulling = false, .pruning = false}).bounds();
    return b.finite() && !b.empty();
}

std::string repeatOverlap(const Bounds3& b, Vec3 cell, Vec3 count) {
    for (int i = 0; i < 3; ++i) {
        if (count[i] <= 0) continue;
        const float extent = std::fmax(std::fabs(b.lo[i]), std::fabs(b.hi[i]));
        if (!(extent <= 0.5f * cell[i])) {
            return "the child reaches " + std::to_string(extent) + " from its origin along axis " +
                   std::to_string(i) + "; the cell must be at least twice that (" +
                   std::to_string(2 * extent) + ") so copies do not overlap";
        }
    }
    return "";
}

void allowObjectKeys(const Reader& r, const std::string& type,
                     const std::vector<const char*>& extra) {
    std::vector<const char*> keys = {"type", "material", "translate", "rotate", "scale"};
    keys.insert(keys.end(), extra.begin(), extra.end());
    for (auto it = r.value().begin(); it != r.value().end(); ++it) {
        bool ok = false;
        for (const char* k : keys) ok = ok || it.key() == k;
        if (ok) continue;
        std::string list;
        for (const char* k : keys) list += (list.empty() ? "" : ", ") + std::string(k);
        r.failKey(it.key(), "unknown key for a " + type + "; accepted: " + list);
    }
}

NodePtr parseNode(const Reader& r, NodeContext& ctx) {
    r.requireObject("an object node");
    if (ctx.depth >= kMaxObjectDepth) {
        r.fail("objects nest deeper than " + std::to_string(kMaxObjectDepth) +
               " levels; flatten the tree (a union or intersection takes any number of children)");
    }
    struct Level {
        int& depth;
        explicit Level(int& d) : depth(++d) {}
        ~Level() { --depth; }
    } level(ctx.depth);
    // Shorthand for a grid object: {"grid": "field.sdfg", ...} is {"type": "grid", "file": ...}.
    if (!r.has("type") && r.has("grid")) {
        r.allowKeys({"grid", "material", "translate", "rotate", "scale"});
        return finishNode(r, requestGridFile(r, ctx, "grid"), ctx);
    }
    // A mesh baked on load: {"mesh": "bunny.obj", "resolution": 128, "method": "exact", ...}, any
    // key of the bake option table (bake/bake_options.h).
    if (!r.has("type") && r.has("mesh")) {
        std::vector<std::string> keys = {"mesh",     "frame",     "dynamic", "play",
                                         "material", "translate", "rotate",  "scale"};
        for (const char* k : bakeOptionKeys(true)) keys.push_back(k);
        r.allowKeys(keys);
        return finishNode(r, requestMesh(r, ctx), ctx);
    }
    const std::string type = r.string("type");
    if (NodePtr n = parsePrimitive(r, type)) return finishNode(r, n, ctx);
    for (const OperatorParser& o : kOperators)
        if (type == o.name) return finishNode(r, o.parse(r, ctx, type), ctx);
    r.failKey("type", "unknown object type '" + type + "'; accepted: " + objectTypeNames());
}

}  // namespace sdft
