// Scene-file object trees to field nodes (internal to the scene module).
#pragma once

#include <map>
#include <string>

#include "json_reader.h"
#include "sdftrace/field/node.h"

namespace sdft {

// `materials` maps names to indices in the scene's material table.
NodePtr parseNode(const json_reader::Reader& r, const std::map<std::string, int>& materials);

}  // namespace sdft
