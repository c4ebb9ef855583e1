// Grid files by extension: .sdfg (our format) or .vdb (OpenVDB float level set).
#pragma once

#include <string>

#include "sdftrace/field/grid.h"

namespace sdft {

bool isGridFile(const std::string& path);    // .sdfg or .vdb
Grid loadGridFile(const std::string& path);  // throws InputError naming the file
void saveGridFile(const Grid& grid, const std::string& path);

}  // namespace sdft
