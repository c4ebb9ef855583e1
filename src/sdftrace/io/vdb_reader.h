// sdftrace's own reader of OpenVDB files (docs/file-formats.md, "VDB import"): the float tree
// (Tree_float_5_4_3, full or half precision) of the first float grid, read straight from the file's
// bytes into flat arrays of nodes and leaves. Every size and index it reads is checked against the
// bytes that remain and the structure it builds, and compressed buffers are validated before they
// are decompressed (zlib, c-blosc's blosc_cbuffer_validate), so a corrupt or hostile file is an
// InputError, never a crash or an allocation the file merely asks for. OpenVDB's own reader
// trusts the sizes it reads (a fuzzer found c-blosc reading out of bounds through it). Internal to
// io.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace sdft::vdb {

struct Leaf {
    std::array<int32_t, 3> origin;   // index coordinates of voxel (0, 0, 0), a multiple of 8
    std::array<uint64_t, 8> active;  // value mask, bit (x << 6 | y << 3 | z)
    std::array<float, 512> values;   // x slowest, z fastest (OpenVDB's order)
};

// Internal nodes: 32^3 (upper, children are lower nodes) or 16^3 (lower, children are leaves).
struct Internal {
    std::array<int32_t, 3> origin;
    std::vector<uint64_t> childMask, valueMask;
    std::vector<float> values;      // tile values (meaningful where childMask is off)
    std::vector<int32_t> children;  // per slot: index of the child node or leaf, -1 for a tile
};

struct RootTile {
    std::array<int32_t, 3> origin;  // of a 4096^3 region
    float value;
    bool active;
};

struct Tree {
    float background = 0;
    std::vector<RootTile> tiles;
    std::vector<int32_t> rootChildren;  // indices into upper
    std::vector<Internal> upper, lower;
    std::vector<Leaf> leaves;
    // The value at index coordinate c, as OpenVDB's accessor would return it.
    float value(int32_t x, int32_t y, int32_t z) const;
};

struct FloatGrid {
    std::string name;
    bool levelSet = false;                // grid class metadata "level set"
    double voxelSize = 0;                 // uniform
    std::array<double, 3> translation{};  // world position of index (0, 0, 0)
    Tree tree;
};

// Reads the first float grid of a level-set class if there is one, else the first float grid.
// Throws InputError naming `path` for anything else.
FloatGrid readVdbFile(const std::string& path);

}  // namespace sdft::vdb
