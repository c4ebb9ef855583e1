// Scene-file object trees to field nodes (internal to the scene module).
#pragma once

#include <map>
#include <string>

#include "json_reader.h"
#include "sdftrace/field/grid.h"
#include "sdftrace/field/node.h"
#include "sdftrace/scene/scene.h"

namespace sdft {

// What object parsing needs beyond the JSON: material names, the directory that relative file
// paths start from, and the scene whose asset requests and deferred checks it adds to.
struct NodeContext {
    std::map<std::string, int> materials;  // name -> index in the scene's material table
    std::string baseDir;
    Scene* scene = nullptr;
    std::map<std::string, int> requestIndex;  // request key -> index in scene->assets
    int depth = 0;                            // objects being parsed, outermost first
    double time = 0;  // the scene's instant (seconds): meshes that "play" are posed there
};

// Objects nest at most this deep (parsing, compiling and bounding recurse over the tree; a union
// takes any number of children, so real scenes stay shallow).
constexpr int kMaxObjectDepth = 256;

// What a bake of a subtree needs: finite, non-empty bounds.
inline const char* kUnbounded =
    "unbounded (a plane or a complement?); a bake needs a bounded field";
bool boundedField(const NodePtr& n);
// Why copies of a child with these bounds overlap in a repetition (empty: they do not).
std::string repeatOverlap(const Bounds3& childBounds, Vec3 cell, Vec3 count);

NodePtr parseNode(const json_reader::Reader& r, NodeContext& context);

// Rejects keys of an object of `type` other than the common ones (type, material, translate,
// rotate, scale) and `extra`.
void allowObjectKeys(const json_reader::Reader& r, const std::string& type,
                     const std::vector<const char*>& extra);

// An analytic primitive of the primitive table by its scene-file name (parse_primitive.cpp);
// null when `type` names none.
NodePtr parsePrimitive(const json_reader::Reader& r, const std::string& type);
// "sphere, box, ..., grid": the primitive types, for messages.
std::string primitiveTypeNames();

}  // namespace sdft
