// The .sdfg grid file (docs/file-formats.md): a versioned little-endian header, the payload (dense
// samples, or sparse block flags + surface-block samples) and a checksum. Loading validates the
// header against the file size before any large allocation and rejects truncated, corrupt,
// wrong-version and absurd-size files with an InputError naming the file.
#pragma once

#include <string>

#include "sdftrace/field/grid.h"

namespace sdft {

// Version 1: distances only. Version 2 appends texture coordinates (Liktor 2008, §5.5.2); it is
// written only for grids that carry them, and both versions are read.
constexpr uint32_t kSdfgVersion = 2;

void saveSdfg(const Grid& grid, const std::string& path);  // atomic (temporary name + rename)
Grid loadSdfg(const std::string& path);

// FNV-1a 64 of a byte range (the payload checksum).
uint64_t fnv1a64(const void* data, size_t bytes, uint64_t seed = 0xcbf29ce484222325ull);

}  // namespace sdft
