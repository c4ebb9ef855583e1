// The .sdfg grid file (docs/file-formats.md): a versioned little-endian header, the payload (dense
// samples, or sparse block flags + surface-block samples) and a checksum. Loading validates the
// header against the file size before any large allocation and rejects truncated, corrupt,
// wrong-version and absurd-size files with an InputError naming the file.
#pragma once

#include <string>

#include "sdftrace/field/grid.h"

namespace sdft {

// Version 1: distances only. Version 2 appends texture coordinates (Liktor 2008, §5.5.2); it is
// written only for grids that carry them. Version 3 holds the same sections compressed: chunks of
// byte-shuffled floats compressed by zstd independently (written and read in parallel, each with
// its own checksum). Version 4 (written for dense grids) stores a sparse grid's flags as its
// two-level table (block_table.h: one byte per tile of 8^3 blocks, then the flags of the tiles that
// vary) instead of one byte per block of the bounding box, so that grids 8192 cells across save and
// load in memory that follows their surface. Version 5 (written by default for sparse grids) stores
// a sparse grid as it is in memory: its sample blocks, neighbour entries, cell masks, skip
// distances and Lipschitz codes, so that loading decompresses them into place and computes
// nothing; dense and complete grids are written as version 4. All five are read.
constexpr uint32_t kSdfgVersion = 5;

struct SdfgWriteOptions {
    bool compress = true;  // version 4 (or `version`); false: version 1 or 2, the raw buffers
    int level = 3;         // zstd level (1 fastest .. 19 smallest)
    uint32_t version = 5;  // compressed: 5, or 4 (apron-free samples, tables recomputed on load)
                           // or 3 (flat block flags) for readers of those versions
};

// Atomic (temporary name + rename).
void saveSdfg(const Grid& grid, const std::string& path, const SdfgWriteOptions& options = {});
Grid loadSdfg(const std::string& path);

// What a .sdfg file holds, from its header and tables alone (its samples are not read, nor their
// checksums checked): what `sdftrace info` prints without --full.
struct SdfgSummary {
    uint32_t version = 0;
    GridKind kind = GridKind::Dense;
    GridShape shape;
    int blockSize = 0;     // sparse
    float background = 0;  // sparse
    TexcoordKind texcoords = TexcoordKind::None;
    uint64_t fileBytes = 0;
    uint64_t sampleBytes =
        0;                   // the distances uncompressed (sparse: B^3 own ones per surface block)
    BlockCounts blocks;      // sparse
    size_t memoryBytes = 0;  // about what the grid takes once loaded (Grid::memoryBytes)
};
// Throws InputError naming the file where its header or tables are wrong (the checks loading makes
// before it reads the samples).
SdfgSummary readSdfgSummary(const std::string& path);

// FNV-1a 64 of a byte range (the payload checksum).
uint64_t fnv1a64(const void* data, size_t bytes, uint64_t seed = 0xcbf29ce484222325ull);

}  // namespace sdft
