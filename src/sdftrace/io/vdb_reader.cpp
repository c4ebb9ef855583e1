// The layout read here is OpenVDB's file format 222-224 (OpenVDB 3 to 11): io/Archive (header,
// grid descriptors), math/Maps (transforms), tree/RootNode, InternalNode and LeafNode
// (readTopology, readBuffers) and io/Compression (readCompressedValues).
#include "vdb_reader.h"

#include <blosc.h>
#include <zlib.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>

#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/io/mapped_file.h"

namespace sdft::vdb {

namespace {

constexpr int64_t kMagic = 0x56444220;
constexpr uint32_t kMinVersion = 222, kMaxVersion = 224;
constexpr uint32_t kZip = 0x1, kActiveMask = 0x2, kBlosc = 0x4;
enum Metadata : int8_t {
    kNoMaskOrInactiveVals,
    kNoMaskAndMinusBg,
    kNoMaskAndOneInactiveVal,
    kMaskAndNoInactiveVals,
    kMaskAndOneInactiveVal,
    kMaskAndTwoInactiveVals,
    kNoMaskAndAllVals
};
// Node sizes: upper 32^3 slots of 128^3 voxels, lower 16^3 slots of 8^3, leaves 8^3 voxels.
constexpr int kUpperLog2 = 5, kLowerLog2 = 4, kLeafLog2 = 3;
constexpr int kUpperSlots = 1 << (3 * kUpperLog2), kLowerSlots = 1 << (3 * kLowerLog2);
constexpr int kLeafSize = 1 << (3 * kLeafLog2);
constexpr int kLowerTotal = kLowerLog2 + kLeafLog2;    // log2 of a lower node's extent: 7
constexpr int kUpperTotal = kUpperLog2 + kLowerTotal;  // 12

// The file's bytes, read front to back; every read is bounds-checked.
class Cursor {
  public:
    Cursor(const char* data, size_t size, const std::string& path)
        : m_data(data), m_size(size), m_path(path) {}

    const std::string& path() const { return m_path; }
    [[noreturn]] void fail(const std::string& what) const {
        throw InputError(m_path + ": not a readable OpenVDB file: " + what + " (at byte " +
                         std::to_string(m_pos) + ")");
    }
    void need(uint64_t bytes, const char* what) const {
        if (bytes > m_size - m_pos) fail(std::string("truncated ") + what);
    }
    template <class T>
    T get(const char* what) {
        need(sizeof(T), what);
        T v;
        std::memcpy(&v, m_data + m_pos, sizeof(T));
        m_pos += sizeof(T);
        return v;
    }
    const char* take(uint64_t bytes, const char* what) {
        need(bytes, what);
        const char* p = m_data + m_pos;
        m_pos += bytes;
        return p;
    }
    std::string string(const char* what) {
        const uint32_t n = get<uint32_t>(what);
        return std::string(take(n, what), n);
    }
    void seek(int64_t pos, const char* what) {
        if (pos < 0 || static_cast<uint64_t>(pos) > m_size)
            fail(std::string("bad offset of ") + what);
        m_pos = static_cast<size_t>(pos);
    }
    size_t pos() const { return m_pos; }
    size_t size() const { return m_size; }

  private:
    const char* m_data;
    size_t m_size, m_pos = 0;
    const std::string& m_path;
};

// IEEE 754 half to float.
float halfToFloat(uint16_t h) {
    const uint32_t sign = (h & 0x8000u) << 16, exp = (h >> 10) & 0x1f, man = h & 0x3ffu;
    uint32_t bits;
    if (exp == 0) {
        if (man == 0) {
            bits = sign;
        } else {  // subnormal: normalize
            int e = -1;
            uint32_t m = man;
            do {
                ++e;
                m <<= 1;
            } while (!(m & 0x400u));
            bits = sign | ((127 - 15 - e) << 23) | ((m & 0x3ffu) << 13);
        }
    } else if (exp == 31) {
        bits = sign | 0x7f800000u | (man << 13);
    } else {
        bits = sign | ((exp + 127 - 15) << 23) | (man << 13);
    }
    return std::bit_cast<float>(bits);
}

struct Reader {
    explicit Reader(Cursor& cursor) : c(cursor) {}
    Cursor& c;
    uint32_t compression = 0;
    bool half = false;
    float background = 0;
    const MappedFile* file = nullptr;                 // what the cursor reads
    std::vector<std::array<int32_t, 3>> leafOrigins;  // in topology order
    // The file and the nodes built so far, checked against the memory budget as each node is
    // made (the nodes of a file take from about its size to ~40 times it, where upper nodes'
    // 8 KiB of masks become 256 KiB of tile values and child indices).
    double treeBytes = 0;
    void grow(double bytes) {
        treeBytes += bytes;
        checkMemoryBudget(static_cast<double>(c.size()) + treeBytes, c.path(),
                          "the file and its tree", "resample the level set coarser");
    }
    // Reused by every node this reader decodes.
    std::vector<char> bloscScratch;
    std::vector<uint64_t> selectionScratch;
    std::vector<float> valueScratch;
    std::vector<uint16_t> halfScratch;

    // memcpy, also for zero bytes into an empty buffer (no null pointer handed to memcpy).
    static void copy(char* out, const char* in, uint64_t bytes) {
        if (bytes) std::memcpy(out, in, bytes);
    }

    // io::readData: `bytes` bytes of values, zipped, blosc-compressed or plain. With a null
    // `out`, only steps over them (readBuffers' first pass).
    void readData(char* out, uint64_t bytes) {
        if (!(compression & (kZip | kBlosc))) {
            const char* src = c.take(bytes, "values");
            if (out) copy(out, src, bytes);
            return;
        }
        const int64_t stored = c.get<int64_t>("compressed size");
        if (stored <= 0) {  // stored uncompressed
            if (static_cast<uint64_t>(-stored) != bytes)
                c.fail("uncompressed block of " + std::to_string(-stored) + " bytes, expected " +
                       std::to_string(bytes));
            const char* src = c.take(bytes, "values");
            if (out) copy(out, src, bytes);
            return;
        }
        const char* src = c.take(static_cast<uint64_t>(stored), "compressed values");
        if (!out) return;
        if (compression & kBlosc) {
            size_t nbytes = 0;
            if (blosc_cbuffer_validate(src, static_cast<size_t>(stored), &nbytes) != 0)
                c.fail("corrupt blosc block");
            // OpenVDB may pad small buffers before compressing them.
            if (nbytes < bytes || nbytes > bytes + 256)
                c.fail("blosc block of " + std::to_string(nbytes) + " bytes, expected " +
                       std::to_string(bytes));
            if (nbytes == 0) return;
            bloscScratch.resize(nbytes);
            if (blosc_decompress_ctx(src, bloscScratch.data(), nbytes, 1) !=
                static_cast<int>(nbytes))
                c.fail("corrupt blosc block");
            copy(out, bloscScratch.data(), bytes);
        } else {
            uLongf outLen = static_cast<uLongf>(bytes);
            if (uncompress(reinterpret_cast<Bytef*>(out), &outLen,
                           reinterpret_cast<const Bytef*>(src),
                           static_cast<uLong>(stored)) != Z_OK ||
                outLen != bytes)
                c.fail("corrupt zip block");
        }
    }

    // io::readCompressedValues for a node of `count` values with value mask `mask`. With a null
    // `dest`, only steps over them.
    void readValues(float* dest, int count, const uint64_t* mask) {
        const int8_t meta = c.get<int8_t>("compression metadata");
        if (meta < kNoMaskOrInactiveVals || meta > kNoMaskAndAllVals)
            c.fail("compression metadata " + std::to_string(meta));
        float inactive1 = background;
        float inactive0 = meta == kNoMaskOrInactiveVals ? background : -background;
        if (meta == kNoMaskAndOneInactiveVal || meta == kMaskAndOneInactiveVal ||
            meta == kMaskAndTwoInactiveVals) {
            inactive0 = c.get<float>("inactive value");
            if (meta == kMaskAndTwoInactiveVals) inactive1 = c.get<float>("inactive value");
        }
        const int words = count / 64;
        std::vector<uint64_t>& selection = selectionScratch;
        selection.assign(words, 0);
        if (meta == kMaskAndNoInactiveVals || meta == kMaskAndOneInactiveVal ||
            meta == kMaskAndTwoInactiveVals)
            std::memcpy(selection.data(), c.take(words * 8ull, "selection mask"), words * 8ull);
        int stored = count;
        if ((compression & kActiveMask) && meta != kNoMaskAndAllVals) {
            stored = 0;
            for (int w = 0; w < words; ++w) stored += std::popcount(mask[w]);
        }
        if (!dest) {
            // io::HalfReader reads nothing at all for zero values (readData would read a size).
            if (!half || stored > 0) readData(nullptr, stored * (half ? 2ull : 4ull));
            return;
        }
        std::vector<float>& values = valueScratch;
        values.resize(stored);
        if (half) {
            std::vector<uint16_t>& h = halfScratch;
            h.resize(stored);
            if (stored > 0) readData(reinterpret_cast<char*>(h.data()), stored * 2ull);
            for (int i = 0; i < stored; ++i) values[i] = halfToFloat(h[i]);
        } else {
            readData(reinterpret_cast<char*>(values.data()), stored * 4ull);
        }
        if (stored == count) {
            copy(reinterpret_cast<char*>(dest), reinterpret_cast<const char*>(values.data()),
                 count * sizeof(float));
            return;
        }
        for (int i = 0, t = 0; i < count; ++i) {
            const bool on = (mask[i >> 6] >> (i & 63)) & 1u;
            dest[i] =
                on ? values[t++] : ((selection[i >> 6] >> (i & 63)) & 1u ? inactive1 : inactive0);
        }
    }

    void readMask(std::vector<uint64_t>& m, int slots, const char* what) {
        m.resize(slots / 64);
        std::memcpy(m.data(), c.take(slots / 8, what), slots / 8);
    }

    // InternalNode::readTopology (upper or lower) and, below it, LeafNode::readTopology.
    int32_t readInternal(Tree& t, std::array<int32_t, 3> origin, bool upper) {
        Internal n;
        n.origin = origin;
        const int log2 = upper ? kUpperLog2 : kLowerLog2, slots = upper ? kUpperSlots : kLowerSlots;
        const int childShift = upper ? kLowerTotal : kLeafLog2;
        grow(sizeof(Internal) + slots * (sizeof(float) + sizeof(int32_t) + 2.0 / 8));
        readMask(n.childMask, slots, "child mask");
        readMask(n.valueMask, slots, "value mask");
        n.values.resize(slots);
        readValues(n.values.data(), slots, n.valueMask.data());
        n.children.assign(slots, -1);
        for (int i = 0; i < slots; ++i) {
            if (!((n.childMask[i >> 6] >> (i & 63)) & 1u)) continue;
            const std::array<int32_t, 3> child = {
                origin[0] + ((i >> (2 * log2)) << childShift),
                origin[1] + (((i >> log2) & ((1 << log2) - 1)) << childShift),
                origin[2] + ((i & ((1 << log2) - 1)) << childShift)};
            if (upper) {
                n.children[i] = readInternal(t, child, false);
            } else {
                // The leaf's mask is stored again with its values (readBuffers); the leaves
                // themselves are allocated once, when their number is known.
                c.take(64, "leaf mask");
                n.children[i] = static_cast<int32_t>(leafOrigins.size());
                leafOrigins.push_back(child);
            }
        }
        std::vector<Internal>& list = upper ? t.upper : t.lower;
        list.push_back(std::move(n));
        return static_cast<int32_t>(list.size() - 1);
    }

    void readTopology(Tree& t) {
        if (c.get<int32_t>("buffer count") != 1) c.fail("multi-buffer trees are not supported");
        t.background = background = c.get<float>("background");
        if (!std::isfinite(background)) c.fail("non-finite background");
        const uint32_t numTiles = c.get<uint32_t>("tile count");
        const uint32_t numChildren = c.get<uint32_t>("child count");
        c.need(numTiles * 17ull, "root tiles");
        for (uint32_t i = 0; i < numTiles; ++i) {
            RootTile tile;
            for (int32_t& v : tile.origin) v = c.get<int32_t>("tile origin");
            tile.value = c.get<float>("tile value");
            tile.active = c.get<uint8_t>("tile state") != 0;
            t.tiles.push_back(tile);
        }
        for (uint32_t i = 0; i < numChildren; ++i) {
            std::array<int32_t, 3> origin;
            for (int32_t& v : origin) {
                v = c.get<int32_t>("child origin");
                if (v & ((1 << kUpperTotal) - 1)) c.fail("root child origin not on the 4096 grid");
            }
            for (int32_t child : t.rootChildren)
                if (t.upper[child].origin == origin) c.fail("two root children at one origin");
            t.rootChildren.push_back(readInternal(t, origin, true));
        }
    }

    // LeafNode::readBuffers for every leaf, in the order of the topology: where each leaf's
    // buffer starts (its headers read, its values stepped over; LeafDecoder reads them). The
    // pages read leave our memory every few MiB (the file stays cached).
    void readBuffers(Tree& t) {
        const size_t n = leafOrigins.size();
        grow(static_cast<double>(n) * sizeof(Leaf));
        t.leaves.resize(n);
        constexpr size_t kReleaseBytes = size_t{16} << 20;
        size_t released = c.pos();
        for (size_t i = 0; i < n; ++i) {
            t.leaves[i] = Leaf{leafOrigins[i], c.pos()};
            uint64_t active[8];
            std::memcpy(active, c.take(64, "leaf mask"), 64);
            readValues(nullptr, kLeafSize, active);
            if (c.pos() - released >= kReleaseBytes) {
                file->release(released, c.pos() - released);
                released = c.pos();
            }
        }
        file->release(released, c.pos() - released);
        leafOrigins = {};
    }
};

void skipMetadata(Cursor& c, std::string* gridClass) {
    const uint32_t count = c.get<uint32_t>("metadata count");
    for (uint32_t i = 0; i < count; ++i) {
        const std::string name = c.string("metadata name"), type = c.string("metadata type");
        const uint32_t bytes = c.get<uint32_t>("metadata size");
        const char* value = c.take(bytes, "metadata value");
        if (gridClass && name == "class" && type == "string")
            *gridClass = std::string(value, bytes);
    }
}

struct Vec3d {
    double v[3];
};
Vec3d readVec3d(Cursor& c) {
    Vec3d r;
    for (double& x : r.v) x = c.get<double>("transform");
    return r;
}

// math/Maps: the voxel size and translation of a uniform scale + translation map.
void readTransform(Cursor& c, FloatGrid& g) {
    const std::string type = c.string("transform type");
    Vec3d scale{{1, 1, 1}}, translation{{0, 0, 0}};
    if (type == "UniformScaleMap" || type == "ScaleMap") {
        scale = readVec3d(c);
        c.take(4 * 24, "transform");  // voxel size, inverse scale, 1/scale^2, 1/(2 scale)
    } else if (type == "UniformScaleTranslateMap" || type == "ScaleTranslateMap") {
        translation = readVec3d(c);
        scale = readVec3d(c);
        c.take(4 * 24, "transform");
    } else if (type == "TranslationMap") {
        translation = readVec3d(c);
    } else if (type == "AffineMap") {
        double m[4][4];
        for (auto& row : m)
            for (double& x : row) x = c.get<double>("transform");
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) {
                const bool diagonal = i == j, translationRow = i == 3 && j < 3;
                if (!diagonal && !translationRow && m[i][j] != 0)
                    c.fail(
                        "an affine transform with rotation, shear or projection (accepted: a "
                        "uniform scale and a translation)");
            }
        if (m[3][3] != 1) c.fail("an affine transform with projection");
        scale = {{m[0][0], m[1][1], m[2][2]}};
        translation = {{m[3][0], m[3][1], m[3][2]}};
    } else {
        c.fail("transform '" + type +
               "' (accepted: a uniform scale and a translation: UniformScaleMap, "
               "UniformScaleTranslateMap, ScaleMap, ScaleTranslateMap, TranslationMap, AffineMap)");
    }
    const double h = scale.v[0];
    for (int a = 0; a < 3; ++a) {
        if (!(scale.v[a] > 0) || !std::isfinite(scale.v[a]) || std::fabs(scale.v[a] - h) > 1e-6 * h)
            c.fail("non-uniform or non-positive voxel size (accepted: uniform voxels)");
        if (!std::isfinite(translation.v[a])) c.fail("non-finite translation");
        g.translation[a] = translation.v[a];
    }
    g.voxelSize = h;
}

// The file, mapped; its size checked against the memory budget first (the nodes are checked as
// they are read).
std::shared_ptr<const MappedFile> mapFile(const std::string& path) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) throw InputError(path + ": cannot open grid file (does it exist?)");
    checkMemoryBudget(static_cast<double>(size), path, "the file and its tree",
                      "resample the level set coarser");
    return std::make_shared<const MappedFile>(path, MappedFile::Load::Lazy);
}

}  // namespace

Location Tree::locate(int32_t x, int32_t y, int32_t z) const {
    const int32_t mask = ~((1 << kUpperTotal) - 1);
    const std::array<int32_t, 3> key = {x & mask, y & mask, z & mask};
    for (int32_t u : rootChildren) {
        const Internal& up = upper[u];
        if (up.origin != key) continue;
        const int su = (((x >> kLowerTotal) & 31) << 10) | (((y >> kLowerTotal) & 31) << 5) |
                       ((z >> kLowerTotal) & 31);
        if (up.children[su] < 0) return {-1, 0, up.values[su]};
        const Internal& lo = lower[up.children[su]];
        const int sl = (((x >> kLeafLog2) & 15) << 8) | (((y >> kLeafLog2) & 15) << 4) |
                       ((z >> kLeafLog2) & 15);
        if (lo.children[sl] < 0) return {-1, 0, lo.values[sl]};
        return {lo.children[sl], ((x & 7) << 6) | ((y & 7) << 3) | (z & 7), 0};
    }
    for (const RootTile& t : tiles)
        if (t.origin == key) return {-1, 0, t.value};
    return {-1, 0, background};
}

struct LeafDecoder::Impl {
    explicit Impl(const FloatGrid& g)
        : grid(g), cursor(g.file->data(), g.file->size(), g.path), reader(cursor) {
        reader.compression = g.compression;
        reader.half = g.half;
        reader.background = g.tree.background;
    }
    const FloatGrid& grid;
    Cursor cursor;
    Reader reader;
};

LeafDecoder::LeafDecoder(const FloatGrid& grid) : m_impl(std::make_unique<Impl>(grid)) {}
LeafDecoder::~LeafDecoder() = default;

void LeafDecoder::decode(size_t i, float* values, uint64_t* active) {
    Cursor& c = m_impl->cursor;
    c.seek(static_cast<int64_t>(m_impl->grid.tree.leaves[i].buffer), "a leaf buffer");
    uint64_t mask[8];
    std::memcpy(mask, c.take(64, "leaf mask"), 64);
    m_impl->reader.readValues(values, kLeafSize, mask);
    if (active) std::memcpy(active, mask, 64);
}

FloatGrid readVdbFile(const std::string& path) {
    const std::shared_ptr<const MappedFile> file = mapFile(path);
    Cursor c(file->data(), file->size(), path);
    if (file->size() < 8 || c.get<int64_t>("magic") != kMagic)
        throw InputError(path + ": not an OpenVDB file (no VDB magic number)");
    const uint32_t version = c.get<uint32_t>("version");
    if (version < kMinVersion || version > kMaxVersion)
        throw InputError(path + ": OpenVDB file format " + std::to_string(version) +
                         " (accepted: 222 to 224, written by OpenVDB 3 to 11; re-save the file "
                         "with one of those)");
    c.get<uint32_t>("library version");
    c.get<uint32_t>("library version");
    const bool hasOffsets = c.get<uint8_t>("offsets flag") != 0;
    c.take(36, "uuid");
    skipMetadata(c, nullptr);
    const int32_t gridCount = c.get<int32_t>("grid count");
    if (gridCount < 0) c.fail("negative grid count");
    FloatGrid found;
    bool have = false;
    for (int32_t g = 0; g < gridCount; ++g) {
        const std::string name = c.string("grid name");
        std::string type = c.string("grid type");
        const std::string suffix = "_HalfFloat";
        const bool half = type.size() > suffix.size() &&
                          type.compare(type.size() - suffix.size(), suffix.size(), suffix) == 0;
        if (half) type.resize(type.size() - suffix.size());
        const std::string parent = c.string("instance parent");
        c.get<int64_t>("grid position");
        c.get<int64_t>("block position");
        const int64_t end = c.get<int64_t>("end position");
        const bool wanted =
            type == "Tree_float_5_4_3" && parent.empty() && !(have && found.levelSet);
        if (!wanted) {
            if (hasOffsets && end > static_cast<int64_t>(c.pos())) {
                c.seek(end, "the next grid");
                continue;
            }
            if (have) return found;
            throw InputError(path + ": grid '" + name + "' (" + type +
                             ") comes before any float grid and cannot be skipped");
        }
        FloatGrid grid;
        grid.name = name;
        grid.path = path;
        grid.file = file;
        Reader r(c);
        r.file = file.get();
        r.half = half;
        r.compression = c.get<uint32_t>("compression");
        if (r.compression > (kZip | kActiveMask | kBlosc))
            c.fail("compression flags " + std::to_string(r.compression));
        std::string gridClass;
        skipMetadata(c, &gridClass);
        grid.levelSet = gridClass == "level set";
        readTransform(c, grid);
        grid.compression = r.compression;
        grid.half = half;
        r.readTopology(grid.tree);
        r.readBuffers(grid.tree);
        if (!have || (grid.levelSet && !found.levelSet)) {
            found = std::move(grid);
            have = true;
        }
        if (found.levelSet) return found;
    }
    if (!have)
        throw InputError(path + ": no float grid in the file (accepted: a FloatGrid level set)");
    return found;
}

}  // namespace sdft::vdb
