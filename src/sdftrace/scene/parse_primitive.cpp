// Scene-file objects of the analytic primitives: one parse function per row of the primitive
// table (field/primitive_table.h), paired with it by name below, so a new row without a parse
// function does not compile.
#include <cmath>
#include <string>
#include <vector>

#include "parse_node.h"
#include "sdftrace/field/primitive_table.h"

namespace sdft {

using json_reader::nonNegative;
using json_reader::positive;
using json_reader::Reader;

namespace {

NodePtr parseSphere(const Reader& r) {
    allowObjectKeys(r, "sphere", {"radius"});
    return node::sphere(r.number("radius", positive, "a positive radius"));
}

NodePtr parseBox(const Reader& r) {
    allowObjectKeys(r, "box", {"size"});
    return node::box(r.vec3("size", positive, "positive edge lengths") * 0.5f);
}

NodePtr parseRoundBox(const Reader& r) {
    allowObjectKeys(r, "round_box", {"size", "radius"});
    const Vec3 half = r.vec3("size", positive, "positive edge lengths") * 0.5f;
    const float radius = r.number("radius", nonNegative, "a non-negative edge radius");
    if (radius > minComponent(half)) r.failKey("radius", "must not exceed half the smallest edge");
    return node::roundBox(half, radius);
}

NodePtr parseTorus(const Reader& r) {
    allowObjectKeys(r, "torus", {"major_radius", "minor_radius"});
    const float major = r.number("major_radius", positive, "a positive ring radius");
    const float minor = r.number("minor_radius", positive, "a positive tube radius");
    return node::torus(major, minor);
}

NodePtr parseCapsule(const Reader& r) {
    allowObjectKeys(r, "capsule", {"a", "b", "radius"});
    return node::capsule(r.vec3("a"), r.vec3("b"),
                         r.number("radius", positive, "a positive radius"));
}

NodePtr parseCylinder(const Reader& r) {
    allowObjectKeys(r, "cylinder", {"radius", "height"});
    const float radius = r.number("radius", positive, "a positive radius");
    return node::cylinder(radius, 0.5f * r.number("height", positive, "a positive height"));
}

NodePtr parseCone(const Reader& r) {
    allowObjectKeys(r, "cone", {"radius", "height"});
    const float radius = r.number("radius", positive, "a positive base radius");
    return node::cone(radius, r.number("height", positive, "a positive height"));
}

NodePtr parsePlane(const Reader& r) {
    allowObjectKeys(r, "plane", {"normal", "distance"});
    const Vec3 normal = r.vec3("normal");
    if (length(normal) <= 0) r.failKey("normal", "expected a non-zero normal");
    // Solid on the side opposite the normal: n.p <= distance.
    return node::plane(normal, -r.number("distance", 0.0f, json_reader::anyFinite, "a number"));
}

NodePtr parseEllipsoid(const Reader& r) {
    allowObjectKeys(r, "ellipsoid", {"radii"});
    return node::ellipsoid(r.vec3("radii", positive, "positive semi-axes"));
}

NodePtr parseOctahedron(const Reader& r) {
    allowObjectKeys(r, "octahedron", {"size"});
    return node::octahedron(r.number("size", positive, "a positive centre-to-vertex size"));
}

NodePtr parseDodecahedron(const Reader& r) {
    allowObjectKeys(r, "dodecahedron", {"radius"});
    return node::dodecahedron(r.number("radius", positive, "a positive inradius"));
}

// Liktor 2008, fig. 1: metaballs with a threshold below the sum of their strengths.
NodePtr parseBlobs(const Reader& r) {
    allowObjectKeys(r, "blobs", {"blobs", "threshold"});
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
    const float threshold = r.number("threshold", 0.5f, positive, "a positive threshold");
    if (threshold >= total) {
        r.failKey("threshold", "must be below the sum of the blob strengths (" +
                                   std::to_string(total) + "), or no surface exists");
    }
    return node::blobs(blobs, threshold);
}

struct PrimitiveParser {
    const char* name;
    NodePtr (*parse)(const Reader&);
};

constexpr PrimitiveParser kParsers[] = {
#define SDFT_PRIMITIVE_PARSER(Kind, name, ...) {name, &parse##Kind},
    SDFT_PRIMITIVES(SDFT_PRIMITIVE_PARSER)
#undef SDFT_PRIMITIVE_PARSER
};

}  // namespace

NodePtr parsePrimitive(const Reader& r, const std::string& type) {
    for (const PrimitiveParser& p : kParsers)
        if (type == p.name) return p.parse(r);
    return nullptr;
}

std::string primitiveTypeNames() {
    std::string names;
    for (const PrimitiveParser& p : kParsers) names += std::string(p.name) + ", ";
    return names + "grid";
}

}  // namespace sdft
