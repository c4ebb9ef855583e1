// The compressed .sdfg layout's headers and chunks (docs/file-formats.md), shared by the
// single-process writer (sdfg_io.cpp) and the one every rank of a distributed bake writes parts of
// (cluster/distributed_bake.cpp).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sdftrace/field/grid.h"

namespace sdft {

inline constexpr char kSdfgMagic[4] = {'S', 'D', 'F', 'G'};
inline constexpr uint32_t kSdfgChunkBytes = 1u << 22;  // uncompressed bytes per chunk (4 MiB)

// Fixed 64-byte header; all fields little-endian (the formats supported are little-endian hosts).
struct SdfgHeader {
    char magic[4];
    uint32_t version;
    uint32_t kind;
    int32_t cells[3];
    float origin[3];
    float voxelSize;
    uint32_t blockSize;
    float background;
    uint64_t payloadBytes;
    uint64_t checksum;
};
static_assert(sizeof(SdfgHeader) == 64, "the .sdfg header is 64 bytes");

// After the 64-byte header of a version-3 to -5 file.
struct SdfgCompressedHeader {
    uint32_t texKind;     // 0: no texture coordinates; else TexcoordKind
    uint32_t chunkBytes;  // uncompressed bytes per chunk (the last of a section may be shorter)
    // Stored samples: dense, every vertex; sparse, (B+1)^3 per surface block (versions 3 and 4)
    // or B^3 per sample block (version 5).
    uint64_t sampleCount;
    // Sparse: the apron samples kept explicitly (versions 3 and 4, block_aprons.h) or the sample
    // blocks past the surface ones (version 5).
    uint64_t apronCount;
    uint64_t chunkCount;  // then chunkCount u64 compressed sizes, then the chunks
};
static_assert(sizeof(SdfgCompressedHeader) == 32);

// Version 4 follows it with the number of own pages of the block table (sparse; 0 when dense),
// which sizes the section of their flags; version 5 (sparse) with the stored grid's surface
// block count and Lipschitz bounds too.
struct SdfgTableHeader {
    uint64_t ownPages;
    uint64_t surfaceBlocks;            // version 5
    float lipschitz, gentleLipschitz;  // version 5
};
static_assert(sizeof(SdfgTableHeader) == 24);

// The header's fields that describe a grid (payload size and checksum left to the writer).
SdfgHeader sdfgHeader(const GridShape& shape, GridKind kind, int blockSize, float background,
                      uint32_t version);

// One chunk of `bytes` at `src`, its 4-byte words byte-shuffled first where `floats` (in
// `scratch`), compressed by zstd at `level` with its checksum. Throws InputError naming `path`.
std::vector<char> compressSdfgChunk(const char* src, uint64_t bytes, bool floats, int level,
                                    std::vector<char>& scratch, const std::string& path);

}  // namespace sdft
