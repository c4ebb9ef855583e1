#include "parse_node.h"

#include <cmath>
#include <filesystem>
#include <vector>

#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/bake/texture_coords.h"
#include "sdftrace/field/noise.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/io/grid_file.h"
#include "sdftrace/io/mesh_file.h"
#include "sdftrace/io/mesh_io.h"

namespace sdft {

using json_reader::nonNegative;
using json_reader::positive;
using json_reader::Reader;

namespace {

const char* kPrimitiveTypes =
    "sphere, box, round_box, torus, capsule, cylinder, cone, plane, ellipsoid, octahedron, "
    "dodecahedron, blobs, grid";
const char* kOperatorTypes =
    "union, intersection, difference, complement, smooth_union, smooth_intersection, "
    "smooth_difference, morph, translate, rotate, scale, repeat, displace";

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

NodePtr parseBlobs(const Reader& r) {
    if (!r.has("blobs"))
        r.fail("missing required key 'blobs' (an array of {center, radius, strength})");
    Reader list = r.child("blobs");
    list.requireArray("a list of blobs");
    if (list.value().empty() || list.value().size() > 256) list.fail("expected 1 to 256 blobs");
    std::vector<node::Blob> blobs;
    float total = 0;
    for (size_t i = 0; i < list.value().size(); ++i) {
        Reader b = list.element(i);
        b.requireObject("a blob");
        b.allowKeys({"center", "radius", "strength"});
        node::Blob blob{b.vec3("center"), b.number("radius", positive, "a positive support radius"),
                        b.number("strength", 1.0f, positive, "a positive strength")};
        total += blob.strength;
        blobs.push_back(blob);
    }
    float threshold = r.number("threshold", 0.5f, positive, "a positive threshold");
    if (threshold >= total) {
        r.failKey("threshold", "must be below the sum of the blob strengths (" +
                                   std::to_string(total) + "), or no surface exists");
    }
    return node::blobs(blobs, threshold);
}

// A path from the scene file, relative to its directory unless absolute.
std::filesystem::path resolvePath(const NodeContext& ctx, const std::string& file) {
    std::filesystem::path path(file);
    if (path.is_relative() && !ctx.baseDir.empty())
        path = std::filesystem::path(ctx.baseDir) / path;
    return path;
}

// A grid file, relative to the scene file's directory; its errors carry the JSON path too.
std::shared_ptr<const Grid> loadGridObject(const Reader& r, NodeContext& ctx,
                                           const char* jsonKey = "file") {
    std::string file = r.string(jsonKey);
    std::filesystem::path path = resolvePath(ctx, file);
    std::string key = path.lexically_normal().string();
    auto it = ctx.grids.find(key);
    if (it != ctx.grids.end()) return it->second;
    if (!isGridFile(key))
        r.failKey(jsonKey, "unsupported grid file '" + file + "'; accepted: .sdfg, .vdb");
    try {
        auto grid = std::make_shared<const Grid>(loadGridFile(key));
        ctx.grids[key] = grid;
        return grid;
    } catch (const InputError& e) {
        r.failKey(jsonKey, e.what());
    }
}

// A mesh file (relative to the scene file) baked to a sparse grid on load; the same file with the
// same options is baked once.
std::shared_ptr<const Grid> bakeMeshObject(const Reader& r, NodeContext& ctx) {
    std::string file = r.string("mesh");
    std::filesystem::path path = resolvePath(ctx, file);
    if (!isMeshFile(path.string())) {
        r.failKey("mesh", "unsupported mesh file '" + file +
                              "'; accepted: .obj, .ply, .stl, .off, .gltf, .glb");
    }
    SampleOptions o;
    o.resolution = r.integer("resolution", 128, 8, 1024);
    std::string method = r.string("method", "exact");
    MeshBakeOptions bake;
    if (!parseMeshBakeMethod(method, bake.method))
        r.failKey("method", "unknown method '" + method + "'; accepted: " + kMeshBakeMethods);
    std::string sign = r.string("sign", "winding");
    if (!parseSignMethod(sign, bake.sign))
        r.failKey("sign", "unknown sign '" + sign + "'; accepted: " + kSignMethods);
    o.bandVoxels = r.number(
        "band", 3.0f, [](double v) { return v >= 2 && v <= 64; }, "a band in [2, 64] voxels");
    bake.sampling = o;
    try {
        validateMeshBakeOptions(bake);
    } catch (const InputError& e) {
        r.failKey("sign", e.what());
    }
    std::string key = path.lexically_normal().string() + "|" + method + "|" + sign + "|" +
                      std::to_string(o.resolution) + "|" + std::to_string(o.bandVoxels);
    auto it = ctx.grids.find(key);
    if (it != ctx.grids.end()) return it->second;
    try {
        TriangleMesh mesh = loadMesh(path.string());
        auto grid = std::make_shared<const Grid>(bakeMesh(mesh, bake).grid);
        ctx.grids[key] = grid;
        return grid;
    } catch (const InputError& e) {
        r.failKey("mesh", e.what());
    }
}

// {"type": "bake", "child": {...}}: the child's field sampled into a sparse grid on load,
// optionally with projected texture coordinates (Liktor 2008, §5.5.2).
std::shared_ptr<const Grid> bakeSubtree(const Reader& r, NodeContext& ctx) {
    const NodePtr child = parseSingleChild(r, ctx);
    const Tape tape = compileTape(child, {.boundsCulling = false});
    if (!tape.bounds().finite() || tape.bounds().empty())
        r.failKey("child", "unbounded (a plane or a complement?); a bake needs a bounded field");
    SampleOptions o;
    o.resolution = r.integer("resolution", 96, 8, 1024);
    o.bandVoxels = r.number(
        "band", 3.0f, [](double v) { return v >= 2 && v <= 64; }, "a band in [2, 64] voxels");
    Grid grid = sampleGrid(tape, tape.bounds(), o);
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
        bakeTexcoords(
            grid, [&tape](Vec3 p) { return tape.eval(p); }, t);
    } else if (r.has("texcoord_axis") || r.has("texcoord_center")) {
        r.fail("texcoord_axis and texcoord_center need \"texcoords\": \"sphere\" or \"cylinder\"");
    }
    return std::make_shared<const Grid>(std::move(grid));
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

}  // namespace

NodePtr parseNode(const Reader& r, NodeContext& mats) {
    r.requireObject("an object node");
    // Shorthand for a grid object: {"grid": "field.sdfg", ...} is {"type": "grid", "file": ...}.
    if (!r.has("type") && r.has("grid")) {
        r.allowKeys({"grid", "material", "translate", "rotate", "scale"});
        return finishNode(r, node::grid(loadGridObject(r, mats, "grid")), mats);
    }
    // A mesh baked on load: {"mesh": "bunny.obj", "resolution": 128, "method": "exact", "sign":
    // "winding", "band": 3}.
    if (!r.has("type") && r.has("mesh")) {
        r.allowKeys({"mesh", "resolution", "method", "sign", "band", "material", "translate",
                     "rotate", "scale"});
        return finishNode(r, node::grid(bakeMeshObject(r, mats)), mats);
    }
    std::string type = r.string("type");
    const char* common[] = {"type", "material", "translate", "rotate", "scale"};
    auto allow = [&](std::initializer_list<const char*> extra) {
        std::vector<const char*> keys(std::begin(common), std::end(common));
        keys.insert(keys.end(), extra.begin(), extra.end());
        for (auto it = r.value().begin(); it != r.value().end(); ++it) {
            bool ok = false;
            for (const char* k : keys) ok = ok || it.key() == k;
            if (!ok) {
                std::string list;
                for (const char* k : keys) list += (list.empty() ? "" : ", ") + std::string(k);
                r.failKey(it.key(), "unknown key for a " + type + "; accepted: " + list);
            }
        }
    };

    NodePtr n;
    if (type == "sphere") {
        allow({"radius"});
        n = node::sphere(r.number("radius", positive, "a positive radius"));
    } else if (type == "box") {
        allow({"size"});
        n = node::box(r.vec3("size", positive, "positive edge lengths") * 0.5f);
    } else if (type == "round_box") {
        allow({"size", "radius"});
        Vec3 half = r.vec3("size", positive, "positive edge lengths") * 0.5f;
        float radius = r.number("radius", nonNegative, "a non-negative edge radius");
        if (radius > minComponent(half))
            r.failKey("radius", "must not exceed half the smallest edge");
        n = node::roundBox(half, radius);
    } else if (type == "torus") {
        allow({"major_radius", "minor_radius"});
        float R = r.number("major_radius", positive, "a positive ring radius");
        float rr = r.number("minor_radius", positive, "a positive tube radius");
        n = node::torus(R, rr);
    } else if (type == "capsule") {
        allow({"a", "b", "radius"});
        n = node::capsule(r.vec3("a"), r.vec3("b"),
                          r.number("radius", positive, "a positive radius"));
    } else if (type == "cylinder") {
        allow({"radius", "height"});
        float radius = r.number("radius", positive, "a positive radius");
        n = node::cylinder(radius, 0.5f * r.number("height", positive, "a positive height"));
    } else if (type == "cone") {
        allow({"radius", "height"});
        float radius = r.number("radius", positive, "a positive base radius");
        n = node::cone(radius, r.number("height", positive, "a positive height"));
    } else if (type == "plane") {
        allow({"normal", "distance"});
        Vec3 normal = r.vec3("normal");
        if (length(normal) <= 0) r.failKey("normal", "expected a non-zero normal");
        // Solid on the side opposite the normal: n.p <= distance.
        n = node::plane(normal, -r.number("distance", 0.0f, json_reader::anyFinite, "a number"));
    } else if (type == "ellipsoid") {
        allow({"radii"});
        n = node::ellipsoid(r.vec3("radii", positive, "positive semi-axes"));
    } else if (type == "octahedron") {
        allow({"size"});
        n = node::octahedron(r.number("size", positive, "a positive centre-to-vertex size"));
    } else if (type == "dodecahedron") {
        allow({"radius"});
        n = node::dodecahedron(r.number("radius", positive, "a positive inradius"));
    } else if (type == "blobs") {
        allow({"blobs", "threshold"});
        n = parseBlobs(r);
    } else if (type == "grid") {
        allow({"file"});
        n = node::grid(loadGridObject(r, mats));
    } else if (type == "union" || type == "intersection") {
        allow({"children"});
        auto c = parseChildren(r, mats, 1, 100000);
        n = type == "union" ? node::unite(c) : node::intersect(c);
    } else if (type == "difference") {
        allow({"children"});
        auto c = parseChildren(r, mats, 2, 100000);
        NodePtr cutters = c.size() == 2 ? c[1] : node::unite({c.begin() + 1, c.end()});
        n = node::subtract(c[0], cutters);
    } else if (type == "complement") {
        allow({"child"});
        n = node::complement(parseSingleChild(r, mats));
    } else if (type == "smooth_union" || type == "smooth_intersection" ||
               type == "smooth_difference") {
        allow({"children", "k"});
        float k = r.number("k", nonNegative, "a non-negative blend radius");
        auto c = parseChildren(r, mats, 2, 100000);
        if (type == "smooth_difference") {
            NodePtr cutters = c.size() == 2 ? c[1] : node::unite({c.begin() + 1, c.end()});
            n = node::smoothDifference(c[0], cutters, k);
        } else {
            n = c[0];
            for (size_t i = 1; i < c.size(); ++i)
                n = type == "smooth_union" ? node::smoothUnion(n, c[i], k)
                                           : node::smoothIntersection(n, c[i], k);
        }
    } else if (type == "morph") {
        allow({"children", "weight"});
        float w = r.number(
            "weight", [](double v) { return v >= 0 && v <= 1; }, "a weight in [0, 1]");
        auto c = parseChildren(r, mats, 2, 2);
        n = node::morph(c[0], c[1], w);
    } else if (type == "bake") {
        allow({"child", "resolution", "band", "texcoords", "texcoord_axis", "texcoord_center"});
        n = node::grid(bakeSubtree(r, mats));
    } else if (type == "translate") {
        allow({"child", "offset"});
        n = node::translate(parseSingleChild(r, mats), r.vec3("offset"));
    } else if (type == "rotate") {
        allow({"child", "axis", "angle"});
        Vec3 axis = r.vec3("axis");
        if (length(axis) <= 0) r.failKey("axis", "expected a non-zero axis");
        float angle = r.number("angle", json_reader::anyFinite, "an angle in degrees");
        n = node::rotate(parseSingleChild(r, mats), rotationAxisAngle(axis, angle));
    } else if (type == "scale") {
        allow({"child", "factors"});
        if (!r.has("factors")) r.fail("missing required key 'factors' (a number or 3 numbers)");
        n = node::scale(parseSingleChild(r, mats), parseScale(r, "factors"));
    } else if (type == "repeat") {
        allow({"child", "cell", "count"});
        Vec3 cell = r.vec3("cell", positive, "positive cell sizes");
        Vec3 count = r.vec3(
            "count", [](double v) { return v >= 0 && v <= 1000 && v == std::floor(v); },
            "whole numbers of copies per side in [0, 1000]");
        NodePtr child = parseSingleChild(r, mats);
        Bounds3 b = nodeBounds(*child);
        for (int i = 0; i < 3; ++i) {
            if (count[i] <= 0) continue;
            float extent = std::fmax(std::fabs(b.lo[i]), std::fabs(b.hi[i]));
            if (!(extent <= 0.5f * cell[i])) {
                r.failKey("cell", "the child reaches " + std::to_string(extent) +
                                      " from its origin along axis " + std::to_string(i) +
                                      "; the cell must be at least twice that (" +
                                      std::to_string(2 * extent) + ") so copies do not overlap");
            }
        }
        n = node::repeat(child, cell, count);
    } else if (type == "displace") {
        allow({"child", "amplitude", "frequency", "octaves", "gain"});
        float amplitude = r.number("amplitude", nonNegative, "a non-negative amplitude");
        float frequency = r.number("frequency", 1.0f, positive, "a positive frequency");
        int octaves = r.integer("octaves", 3, 1, 12);
        float gain = r.number(
            "gain", 0.5f, [](double v) { return v > 0 && v < 1; }, "a gain in (0, 1)");
        n = node::displace(parseSingleChild(r, mats), amplitude, frequency, octaves, gain);
    } else {
        r.failKey("type", "unknown object type '" + type + "'; accepted: " + kPrimitiveTypes +
                              ", " + kOperatorTypes);
    }

    return finishNode(r, n, mats);
}

}  // namespace sdft
