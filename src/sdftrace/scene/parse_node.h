// Scene-file object trees to field nodes (internal to the scene module).
#pragma once

#include <map>
#include <string>

#include "json_reader.h"
#include "sdftrace/field/grid.h"
#include "sdftrace/field/node.h"

namespace sdft {

// What object parsing needs beyond the JSON: material names, the directory that relative file
// paths start from, and the grids loaded so far (a file used twice is loaded once).
struct NodeContext {
    std::map<std::string, int> materials;  // name -> index in the scene's material table
    std::string baseDir;
    std::map<std::string, std::shared_ptr<const Grid>> grids;
};

NodePtr parseNode(const json_reader::Reader& r, NodeContext& context);

// Rejects keys of an object of `type` other than the common ones (type, material, translate,
// rotate, scale) and `extra`.
void allowObjectKeys(const json_reader::Reader& r, const std::string& type,
                     std::initializer_list<const char*> extra);

// An analytic primitive of the primitive table by its scene-file name (parse_primitive.cpp);
// null when `type` names none.
NodePtr parsePrimitive(const json_reader::Reader& r, const std::string& type);
// "sphere, box, ..., grid": the primitive types, for messages.
std::string primitiveTypeNames();

}  // namespace sdft
