// sdftrace's own reader of OpenVDB files (docs/file-formats.md, "VDB import"): the float tree
// (Tree_float_5_4_3, full or half precision) of the first float grid, read straight from the file's
// bytes into flat arrays of nodes and leaves. The leaves' values stay in the (mapped) file until a
// LeafDecoder reads them, so that an importer can stream them into its grid without holding the
// whole tree decoded (2 KiB a leaf). Every size and index it reads is checked against the bytes
// that remain and the structure it builds, and compressed buffers are validated before they are
// decompressed (zlib, c-blosc's blosc_cbuffer_validate), so a corrupt or hostile file is an
// InputError, never a crash or an allocation the file merely asks for. OpenVDB's own reader
// trusts the sizes it reads (a fuzzer found c-blosc reading out of bounds through it). Internal to
// io.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace sdft {
class MappedFile;
}

namespace sdft::vdb {

constexpr int kLeafVoxels = 512;

struct Leaf {
    std::array<int32_t, 3> origin;  // index coordinates of voxel (0, 0, 0), a multiple of 8
    uint64_t buffer;                // where its buffer (value mask, then values) starts in the file
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

// Where an index coordinate lies in the tree: in a leaf (its index and the voxel's place in it,
// x << 6 | y << 3 | z), or in a tile, a node's constant value or the background (leaf -1).
struct Location {
    int32_t leaf = -1;
    int voxel = 0;
    float value = 0;
};

struct Tree {
    float background = 0;
    std::vector<RootTile> tiles;
    std::vector<int32_t> rootChildren;  // indices into upper
    std::vector<Internal> upper, lower;
    std::vector<Leaf> leaves;  // in the file's order
    Location locate(int32_t x, int32_t y, int32_t z) const;
};

struct FloatGrid {
    std::string name, path;
    bool levelSet = false;                // grid class metadata "level set"
    double voxelSize = 0;                 // uniform
    std::array<double, 3> translation{};  // world position of index (0, 0, 0)
    Tree tree;
    // The file the leaves' buffers lie in, and their encoding.
    std::shared_ptr<const MappedFile> file;
    uint32_t compression = 0;
    bool half = false;
};

// Decodes leaves' buffers from the grid's file, any leaf in any order; one per thread (it keeps
// its scratch buffers). Throws InputError naming the file for a corrupt buffer.
class LeafDecoder {
  public:
    explicit LeafDecoder(const FloatGrid& grid);
    ~LeafDecoder();
    // Leaf i's values, x slowest and z fastest (OpenVDB's order), and its value mask (bit
    // x << 6 | y << 3 | z) when `active` is not null.
    void decode(size_t i, float* values, uint64_t* active = nullptr);

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

// Reads the first float grid of a level-set class if there is one, else the first float grid.
// Throws InputError naming `path` for anything else.
FloatGrid readVdbFile(const std::string& path);

}  // namespace sdft::vdb
