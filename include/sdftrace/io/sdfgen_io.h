// SDFGen's text format (Christopher Batty's SDFGen, also read by many simulators): "ni nj nk",
// the origin (the first sample's position), the spacing dx, then ni*nj*nk values, i fastest. The
// values are samples at origin + (i, j, k) dx: a dense grid of (ni-1)x(nj-1)x(nk-1) cells.
// docs/file-formats.md.
#pragma once

#include <string>

#include "sdftrace/field/grid.h"

namespace sdft {

// Throws InputError naming the file and the line for anything malformed.
Grid loadSdfgen(const std::string& path);
// Every vertex (a sparse grid is written dense), shortest round-trip decimals; atomic.
void saveSdfgen(const Grid& grid, const std::string& path);

}  // namespace sdft
