#include "sdftrace/io/vdb_io.h"

#include <emmintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <utility>

#include "sdftrace/core/error.h"
#include "sdftrace/core/macros.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/field/openvdb_plugin.h"
#include "sdftrace/field/sparse_grid_builder.h"
#include "sdftrace/io/atomic_file.h"
#include "sdftrace/io/mapped_file.h"
#include "vdb_reader.h"

namespace sdft {

namespace {

// A surface block's samples in memory (decision 10): its B^3 own samples and 8 neighbour entries.
constexpr double kBytesPerSurfaceBlock(int B) {
    return B * B * B * sizeof(float) + 8 * sizeof(int32_t);
}

// Every tile of the tree, root tiles and internal nodes' tile slots alike:
// f(value, active, x, y, z, extent) with the tile's first voxel and its edge in voxels.
template <class F>
void forEachTile(const vdb::Tree& t, F&& f) {
    for (const vdb::RootTile& tile : t.tiles)
        f(tile.value, tile.active, tile.origin[0], tile.origin[1], tile.origin[2], 4096);
    auto internal = [&](const std::vector<vdb::Internal>& nodes, int log2, int shift) {
        for (const vdb::Internal& n : nodes)
            for (int i = 0; i < (1 << (3 * log2)); ++i) {
                const auto slot = static_cast<size_t>(i);
                if (n.children[slot] >= 0) continue;
                f(n.values[slot], ((n.valueMask[slot >> 6] >> (slot & 63)) & 1u) != 0,
                  n.origin[0] + ((i >> (2 * log2)) << shift),
                  n.origin[1] + (((i >> log2) & ((1 << log2) - 1)) << shift),
                  n.origin[2] + ((i & ((1 << log2) - 1)) << shift), 1 << shift);
            }
    };
    internal(t.upper, 5, 7);
    internal(t.lower, 4, 3);
}

// Index bounds of active voxels, grown voxel box by voxel box.
struct ActiveBounds {
    std::array<int32_t, 3> lo{}, hi{};
    bool any = false;
    void include(const int32_t a[3], const int32_t b[3]) {
        for (int i = 0; i < 3; ++i) {
            lo[i] = any ? std::min(lo[i], a[i]) : a[i];
            hi[i] = any ? std::max(hi[i], b[i]) : b[i];
        }
        any = true;
    }
    void include(const ActiveBounds& o) {
        if (o.any) include(o.lo.data(), o.hi.data());
    }
    // A leaf's active voxels (mask word w holds x = w; its bit b holds y = b >> 3, z = b & 7).
    void includeLeaf(const std::array<int32_t, 3>& origin, const uint64_t active[8]) {
        uint64_t bits = 0;
        int x0 = 8, x1 = -1;
        for (int w = 0; w < 8; ++w) {
            if (!active[w]) continue;
            bits |= active[w];
            x0 = std::min(x0, w);
            x1 = w;
        }
        if (!bits) return;
        uint8_t rows = 0, cols = 0;  // y and z present
        for (; bits; bits &= bits - 1) {
            const int b = std::countr_zero(bits);
            rows |= static_cast<uint8_t>(1u << (b >> 3));
            cols |= static_cast<uint8_t>(1u << (b & 7));
        }
        const int32_t a[3] = {origin[0] + x0, origin[1] + std::countr_zero(rows),
                              origin[2] + std::countr_zero(cols)};
        const int32_t b[3] = {origin[0] + x1, origin[1] + 7 - std::countl_zero(rows),
                              origin[2] + 7 - std::countl_zero(cols)};
        include(a, b);
    }
    // The active tiles of the tree.
    void includeTiles(const vdb::Tree& t) {
        forEachTile(t, [&](float, bool active, int32_t x, int32_t y, int32_t z, int extent) {
            const int32_t a[3] = {x, y, z}, b[3] = {x + extent - 1, y + extent - 1, z + extent - 1};
            if (active) include(a, b);
        });
    }
};

// Per worker: leaves decoded for the tiles it gathers, kept from tile to tile (its tiles come in
// the file's order, so the next one reads many of the same leaves) and dropped all at once when
// a tile might not fit, never while a tile reads them.
class LeafCache {
  public:
    LeafCache(const vdb::FloatGrid& g, size_t capacity)
        : m_decoder(std::make_unique<vdb::LeafDecoder>(g)),
          m_capacity(capacity),
          m_values(new float[capacity * vdb::kLeafVoxels]),  // touched as leaves are decoded
          m_keys(std::bit_ceil(2 * capacity), -1),
          m_slots(m_keys.size()) {}

    // Room for `leaves` more, made by dropping every leaf if need be.
    void makeRoom(size_t leaves) {
        if (m_used + leaves <= m_capacity) return;
        std::fill(m_keys.begin(), m_keys.end(), -1);
        m_used = 0;
    }
    // Leaf i's 512 values, decoded if they are not here.
    const float* values(int32_t leaf) {
        const size_t mask = m_keys.size() - 1;
        size_t h = (static_cast<uint32_t>(leaf) * 0x9e3779b1u) & mask;
        for (; m_keys[h] >= 0; h = (h + 1) & mask)
            if (m_keys[h] == leaf) return m_values.get() + m_slots[h] * vdb::kLeafVoxels;
        SDFT_CHECK(m_used < m_capacity);
        float* out = m_values.get() + m_used * vdb::kLeafVoxels;
        m_decoder->decode(static_cast<size_t>(leaf), out);
        m_keys[h] = leaf;
        m_slots[h] = m_used++;
        return out;
    }

  private:
    std::unique_ptr<vdb::LeafDecoder> m_decoder;
    size_t m_capacity, m_used = 0;
    std::unique_ptr<float[]> m_values;
    std::vector<int32_t> m_keys;  // open addressing, linear probing
    std::vector<size_t> m_slots;
};

// The tree straight into a sparse block grid: blocks that touch a leaf (or whose corners are near
// or of both signs) get their samples from the tree; every other block lies in one tile region
// and takes its flag from the sign there. Same grid as sampling the dense active region and
// sparsifying it (Grid::sparseFromDense), without the dense array.
class TreeToGrid {
  public:
    // Reads `g`'s leaves from its file and drops its tree once the samples are gathered.
    TreeToGrid(vdb::FloatGrid& g, const std::string& path, const VdbImportOptions& o)
        : m_g(g),
          m_t(g.tree),
          m_path(path),
          m_B(o.blockSize),
          m_V(o.blockSize + 1),
          m_cachedLeaves(o.cachedLeaves) {
        m_gridName = g.name;
        const float h = static_cast<float>(g.voxelSize);
        m_bandVoxels = std::max(o.minBandVoxels, std::fabs(m_t.background) / h * 0.999f);
        m_band = m_bandVoxels * h;
        m_tileFloor = std::min(m_band, std::fabs(m_t.background) / h * 0.999f * h);
        ActiveBounds bounds = scanLeaves();
        bounds.includeTiles(m_t);
        if (!bounds.any) throw InputError(path + ": grid '" + g.name + "' has no active voxels");
        m_lo = bounds.lo;
        m_hi = bounds.hi;
        makeShape(g);
        checkTiles();
        for (int a = 0; a < 3; ++a) {
            m_blocks[a] = (m_shape.cells[a] + m_B - 1) / m_B;
            m_tiles[a] = (m_blocks[a] + kTileBlocks - 1) >> kTileShift;
        }
        m_numTiles = static_cast<size_t>(m_tiles[0]) * m_tiles[1] * m_tiles[2];
        // The tile table (page, skip distance, kind while building) and the surface blocks.
        checkMemoryBudget(
            static_cast<double>(m_numTiles) * 6 +
                static_cast<double>(m_t.leaves.size()) * 8 * m_V * m_V * m_V * sizeof(float),
            path, "the sparse grid's tile table and surface blocks",
            "resample the level set coarser");
        indexUnits();
    }

    Grid build() {
        BlockTable table = buildTable();
        std::vector<LeafBits>().swap(m_leafBits);  // the leaves' bits are read no more
        const size_t surface = table.surfaceBlocks();
        checkMemoryBudget(static_cast<double>(table.flags.size()) * 6 +
                              static_cast<double>(surface) * kBytesPerSurfaceBlock(m_B),
                          m_path,
                          "the samples of " + std::to_string(surface) + " blocks near its surface",
                          "resample the level set coarser");
        // The builder numbers the surface blocks (and refuses more than 2^31 - 1).
        SparseGridBuilder builder(m_shape, m_B, (m_bandVoxels - 1) * m_shape.voxelSize,
                                  std::move(table), m_path);
        sampleSurfaceBlocks(builder);
        // The tree is read no more: its nodes leave before finish() makes the skip tables.
        m_g.tree = vdb::Tree();
        std::vector<int32_t>().swap(m_unitLower);
        std::vector<float>().swap(m_unitValue);
        return builder.finish();
    }

  private:
    // A level set's tiles hold +-background: the band lies wholly in its leaves. A tile inside
    // the band would turn every block of its region into a surface block (a 12 KB file can hold
    // tiles over billions of voxels), so it is refused here, before anything is sized by it.
    void checkTiles() const {
        auto check = [&](float v, int32_t x, int32_t y, int32_t z, int extent) {
            if (std::fabs(v) >= m_tileFloor) return;
            const std::string e = std::to_string(extent);
            throw InputError(m_path + ": grid '" + m_gridName + "' has a tile of " + e +
                             "^3 voxels at (" + std::to_string(x) + ", " + std::to_string(y) +
                             ", " + std::to_string(z) + ") holding " + std::to_string(v) +
                             ", inside the narrow band (|value| < " + std::to_string(m_tileFloor) +
                             "): not a level set (accepted: level sets whose tiles hold "
                             "+-background, as openvdb::tools::pruneLevelSet leaves them)");
        };
        forEachTile(m_t, [&](float v, bool, int32_t x, int32_t y, int32_t z, int extent) {
            check(v, x, y, z, extent);
        });
    }

    void makeShape(const vdb::FloatGrid& g) {
        for (int a = 0; a < 3; ++a) {
            const int64_t dim = static_cast<int64_t>(m_hi[a]) - m_lo[a] + 1;
            if (dim < 2 || dim > 32768)
                throw InputError(m_path + ": active region of " + std::to_string(dim) +
                                 " voxels along an axis (accepted: 2 to 32768)");
            m_shape.cells[a] = static_cast<int>(dim - 1);
            m_shape.origin[a] = static_cast<float>(g.translation[a] + m_lo[a] * g.voxelSize);
            if (!(std::fabs(m_shape.origin[a]) <= kMaxCoordinate))
                throw InputError(m_path + ": the grid lies beyond +-1e9");
        }
        m_shape.voxelSize = static_cast<float>(g.voxelSize);
    }

    // The active region in units of a lower internal node (128^3 voxels): per unit its lower node
    // (or -1) and otherwise its constant value (an upper node's tile, a root tile or the
    // background), so that an 8^3 region is found by two array reads, not a tree descent, and
    // the index follows the tree's nodes, not the bounding box's voxels.
    void indexUnits() {
        for (int a = 0; a < 3; ++a) {
            m_u0[a] = m_lo[a] >> kUnitLog2;
            m_un[a] = (m_hi[a] >> kUnitLog2) - m_u0[a] + 1;
        }
        const size_t numUnits = static_cast<size_t>(m_un[0]) * m_un[1] * m_un[2];
        m_unitLower.assign(numUnits, -1);
        m_unitValue.assign(numUnits, 0.0f);
        for (size_t i = 0; i < m_t.lower.size(); ++i) {
            const auto& o = m_t.lower[i].origin;
            bool inside = true;
            for (int a = 0; a < 3; ++a) {
                const int32_t u = (o[a] >> kUnitLog2) - m_u0[a];
                inside = inside && u >= 0 && u < m_un[a];
            }
            if (inside) m_unitLower[unitOf(o[0], o[1], o[2])] = static_cast<int32_t>(i);
        }
        tbb::parallel_for(size_t(0), numUnits, [&](size_t u) {
            if (m_unitLower[u] >= 0) return;
            const int32_t x = (m_u0[0] + static_cast<int32_t>(u % m_un[0])) << kUnitLog2;
            const int32_t y = (m_u0[1] + static_cast<int32_t>(u / m_un[0] % m_un[1])) << kUnitLog2;
            const int32_t z =
                (m_u0[2] + static_cast<int32_t>(u / (static_cast<size_t>(m_un[0]) * m_un[1])))
                << kUnitLog2;
            m_unitValue[u] = m_t.locate(x, y, z).value;  // no leaf: the unit has no lower node
        });
    }

    size_t unitOf(int32_t x, int32_t y, int32_t z) const {
        return (static_cast<size_t>((z >> kUnitLog2) - m_u0[2]) * m_un[1] +
                ((y >> kUnitLog2) - m_u0[1])) *
                   m_un[0] +
               ((x >> kUnitLog2) - m_u0[0]);
    }

    // The 8^3 region holding voxel (x, y, z) of the active region: its leaf, or -1 and its
    // constant value.
    int32_t regionAt(int32_t x, int32_t y, int32_t z, float& value) const {
        const size_t u = unitOf(x, y, z);
        const int32_t n = m_unitLower[u];
        if (n < 0) {
            value = m_unitValue[u];
            return -1;
        }
        const vdb::Internal& lower = m_t.lower[static_cast<size_t>(n)];
        const int slot = (((x >> 3) & 15) << 8) | (((y >> 3) & 15) << 4) | ((z >> 3) & 15);
        const int32_t leaf = lower.children[static_cast<size_t>(slot)];
        if (leaf < 0) value = lower.values[static_cast<size_t>(slot)];
        return leaf;
    }

    // The 8^3 regions the vertices of one tile's blocks read (and one more per axis), looked up
    // once per tile: classify and gatherBlock read up to 8 regions per block.
    struct TileRegions {
        static constexpr int kMax = 11;  // a tile's vertices span at most 64 + 1 voxels
        // The most regions a tile of blocks of B lists (tileRegions: its span's regions and one
        // more per axis).
        static constexpr int regionsPerTile(int B) {
            const int n = (kTileBlocks * B + 7) / 8 + 2;
            return n * n * n;
        }
        int32_t first[3] = {0, 0, 0};  // region coordinate (voxel >> 3) of entry 0
        int n[3] = {0, 0, 0};
        int32_t leaf[kMax * kMax * kMax];
        float value[kMax * kMax * kMax];
        // Region (rx, ry, rz) (voxel >> 3): its leaf, or -1 and its value.
        int32_t at(int32_t rx, int32_t ry, int32_t rz, float& v) const {
            const int i = ((rz - first[2]) * n[1] + (ry - first[1])) * n[0] + (rx - first[0]);
            v = value[i];
            return leaf[i];
        }
    };

    void tileRegions(const int tile[3], TileRegions& tr) const {
        for (int a = 0; a < 3; ++a) {
            const int span = kTileBlocks * m_B;
            const int32_t v0 = m_lo[a] + std::min(tile[a] * span, m_shape.cells[a]);
            const int32_t v1 = m_lo[a] + std::min((tile[a] + 1) * span, m_shape.cells[a]);
            tr.first[a] = v0 >> 3;
            tr.n[a] = (v1 >> 3) - tr.first[a] + 2;
        }
        for (int z = 0; z < tr.n[2]; ++z)
            for (int y = 0; y < tr.n[1]; ++y)
                for (int x = 0; x < tr.n[0]; ++x) {
                    const int i = (z * tr.n[1] + y) * tr.n[0] + x;
                    const int32_t o[3] = {(tr.first[0] + x) * 8, (tr.first[1] + y) * 8,
                                          (tr.first[2] + z) * 8};
                    // Past the active region: never read (the vertices clamp).
                    if (o[0] > m_hi[0] || o[1] > m_hi[1] || o[2] > m_hi[2]) {
                        tr.leaf[i] = -1;
                        tr.value[i] = 0;
                        continue;
                    }
                    tr.leaf[i] = regionAt(o[0], o[1], o[2], tr.value[i]);
                }
    }

    // Pass 1: the two-level flag table. A tile of 8^3 blocks whose vertices read no leaf and no
    // value within the band, all of one sign, is constant (pages 0 and 1); every block of the
    // other tiles is classified by its samples' sign and band bits (classify), without gathering
    // them. Pages whose blocks all come out of one flag are then shared too, so the table is the
    // one BlockTable::fromDense makes of the same flags. Nothing is sized by the bounding box
    // but the tile table.
    BlockTable buildTable() const {
        BlockTable t = BlockTable::empty(m_blocks);
        std::vector<uint8_t> kind(m_numTiles);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, m_numTiles, 256), [&](const auto& range) {
            for (size_t tile = range.begin(); tile != range.end(); ++tile) {
                const int c[3] = {
                    static_cast<int>(tile % m_tiles[0]),
                    static_cast<int>(tile / m_tiles[0] % m_tiles[1]),
                    static_cast<int>(tile / (static_cast<size_t>(m_tiles[0]) * m_tiles[1]))};
                kind[tile] = tileKind(c);
            }
        });
        int32_t next = kFirstOwnPage;
        for (size_t tile = 0; tile < m_numTiles; ++tile)
            t.tilePage[tile] = kind[tile] == 2 ? next++ : kind[tile];
        t.flags.resize(static_cast<size_t>(next) * kPageEntries,
                       static_cast<uint8_t>(BlockFlag::Outside));
        const std::vector<int> own = t.ownTiles();
        tbb::parallel_for(size_t(0), own.size() / 3, [&](size_t p) {
            uint8_t* page = t.flags.data() + (p + kFirstOwnPage) * kPageEntries;
            TileRegions tr;
            tileRegions(&own[3 * p], tr);
            forEachBlockOfTile(m_blocks, own[3 * p], own[3 * p + 1], own[3 * p + 2],
                               [&](int bi, int bj, int bk) {
                                   const int b[3] = {bi, bj, bk};
                                   page[pageLocal(bi, bj, bk)] = classify(b, tr);
                               });
        });
        t.shareConstantPages();
        return t;
    }

    // 0 (outside) or 1 (inside) for a tile whose blocks all take that flag without a look at
    // their samples, else 2. Its vertices span at most two units per axis; in a unit without a
    // lower node the value is constant, in one with a node the 8^3 regions are its slots.
    uint8_t tileKind(const int tile[3]) const {
        int32_t v0[3], v1[3];
        for (int a = 0; a < 3; ++a) {
            const int span = kTileBlocks * m_B;
            v0[a] = m_lo[a] + std::min(tile[a] * span, m_shape.cells[a]);
            v1[a] = m_lo[a] + std::min((tile[a] + 1) * span, m_shape.cells[a]);
        }
        bool anyNeg = false, anyPos = false;
        auto take = [&](float v) {
            anyNeg |= v < 0;
            anyPos |= !(v < 0);
            return std::fabs(v) < m_tileFloor;
        };
        for (int32_t uz = v0[2] >> kUnitLog2; uz <= v1[2] >> kUnitLog2; ++uz)
            for (int32_t uy = v0[1] >> kUnitLog2; uy <= v1[1] >> kUnitLog2; ++uy)
                for (int32_t ux = v0[0] >> kUnitLog2; ux <= v1[0] >> kUnitLog2; ++ux) {
                    const int32_t o[3] = {ux << kUnitLog2, uy << kUnitLog2, uz << kUnitLog2};
                    const size_t u = unitOf(o[0], o[1], o[2]);
                    const int32_t n = m_unitLower[u];
                    if (n < 0) {
                        if (take(m_unitValue[u])) return 2;
                        continue;
                    }
                    const vdb::Internal& lower = m_t.lower[static_cast<size_t>(n)];
                    int s0[3], s1[3];  // the slots the box covers in this node
                    for (int a = 0; a < 3; ++a) {
                        s0[a] = (std::max(v0[a], o[a]) - o[a]) >> 3;
                        s1[a] = (std::min(v1[a], o[a] + (1 << kUnitLog2) - 1) - o[a]) >> 3;
                    }
                    for (int sx = s0[0]; sx <= s1[0]; ++sx)
                        for (int sy = s0[1]; sy <= s1[1]; ++sy)
                            for (int sz = s0[2]; sz <= s1[2]; ++sz) {
                                const size_t slot = static_cast<size_t>(sx << 8 | sy << 4 | sz);
                                if (lower.children[slot] >= 0 || take(lower.values[slot])) return 2;
                            }
                }
        // Tiles of both signs and no leaf between them: two neighbouring voxels hold -background
        // and +background, which no distance field does (they are one voxel apart). Refused, as
        // each block along the meeting would otherwise be a surface block.
        if (anyNeg && anyPos && m_tileFloor > 0.5f * m_shape.voxelSize)
            throw InputError(m_path + ": grid '" + m_gridName +
                             "' has tiles of opposite sign meeting near voxel (" +
                             std::to_string(v0[0]) + ", " + std::to_string(v0[1]) + ", " +
                             std::to_string(v0[2]) +
                             ") with no narrow band between them: not a level set");
        return anyNeg && anyPos ? 2 : anyNeg ? 1 : 0;
    }

    // Per leaf, one bit per voxel (word x, bit y << 3 | z, as the leaf stores them): negative,
    // and within the band.
    struct LeafBits {
        uint64_t negative[8], near[8];
    };

    // Pass 0, over the leaves in the file's order: each decoded once, its bits kept and its pages
    // released; the leaves' active bounds. Also refuses non-finite values (|v| <= FLT_MAX fails
    // for them).
    ActiveBounds scanLeaves() {
        const size_t n = m_t.leaves.size();
        m_leafBits.resize(n);
        std::atomic<bool> finite{true};
        tbb::enumerable_thread_specific<ActiveBounds> bounds;
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const auto& range) {
            vdb::LeafDecoder decoder(m_g);
            alignas(16) float values[vdb::kLeafVoxels];
            uint64_t active[8];
            ActiveBounds& b = bounds.local();
            bool allFinite = true;
            for (size_t l = range.begin(); l != range.end(); ++l) {
                decoder.decode(l, values, active);
                b.includeLeaf(m_t.leaves[l].origin, active);
                allFinite &= leafBits(values, m_leafBits[l]);
            }
            if (!allFinite) finite = false;
            releaseLeaves(range.begin(), range.end());
        });
        if (!finite) throw InputError(m_path + ": non-finite values in grid '" + m_gridName + "'");
        ActiveBounds all;
        for (const ActiveBounds& b : bounds) all.include(b);
        return all;
    }

    // The file's pages of leaves [first, last) (those their buffers hold whole) leave the
    // process's memory; the file stays in the page cache.
    void releaseLeaves(size_t first, size_t last) const {
        if (first >= last) return;
        const uint64_t begin = m_t.leaves[first].buffer;
        const uint64_t end = last < m_t.leaves.size() ? m_t.leaves[last].buffer : m_g.file->size();
        m_g.file->release(begin, end - begin);
    }

    // One leaf's sign and band bits (SSE2, four voxels a step); false if a value is not finite.
    bool leafBits(const float* v, LeafBits& bits) const {
        const __m128 sign = _mm_set1_ps(-0.0f), zero = _mm_setzero_ps(), band = _mm_set1_ps(m_band),
                     largest = _mm_set1_ps(std::numeric_limits<float>::max());
        int allFinite = 0xf;
        for (int x = 0; x < 8; ++x) {
            uint64_t negative = 0, near = 0;
            for (int q = 0; q < 16; ++q) {
                const __m128 f = _mm_load_ps(v + x * 64 + q * 4);
                const __m128 magnitude = _mm_andnot_ps(sign, f);
                negative |= uint64_t(_mm_movemask_ps(_mm_cmplt_ps(f, zero))) << (4 * q);
                near |= uint64_t(_mm_movemask_ps(_mm_cmplt_ps(magnitude, band))) << (4 * q);
                allFinite &= _mm_movemask_ps(_mm_cmple_ps(magnitude, largest));
            }
            bits.negative[x] = negative;
            bits.near[x] = near;
        }
        return allFinite == 0xf;
    }

    // Block b's flag from its (B+1)^3 samples' bits, without gathering them: surface if one is
    // within the band or their signs differ (as Grid::sparseFromDense decides), else inside or
    // outside by their sign. Its vertices per axis span at most two 8-voxel regions, a box in
    // each.
    uint8_t classify(const int b[3], const TileRegions& tr) const {
        int first[3], lo[3][2], hi[3][2];
        for (int a = 0; a < 3; ++a) {
            first[a] = (m_lo[a] + b[a] * m_B) >> 3;
            // The first and last vertex, clamped to the grid as GridView::vertex clamps.
            const int32_t v0 = m_lo[a] + std::min(b[a] * m_B, m_shape.cells[a]),
                          v1 = m_lo[a] + std::min(b[a] * m_B + m_B, m_shape.cells[a]);
            for (int r = 0; r < 2; ++r) {
                const int32_t start = (first[a] + r) * 8;
                lo[a][r] = std::max(v0, start) - start;
                hi[a][r] = std::min(v1, start + 7) - start;
            }
        }
        bool anyNeg = false, anyPos = false, near = false;
        for (int c = 0; c < 8; ++c) {
            const int rx = c & 1, ry = c >> 1 & 1, rz = c >> 2;
            if (lo[0][rx] > hi[0][rx] || lo[1][ry] > hi[1][ry] || lo[2][rz] > hi[2][rz]) continue;
            float v = 0;
            const int32_t leaf = tr.at(first[0] + rx, first[1] + ry, first[2] + rz, v);
            if (leaf < 0) {
                anyNeg |= v < 0;
                anyPos |= !(v < 0);
                near |= std::fabs(v) < m_tileFloor;
                continue;
            }
            // The y rows (bytes) and z bits of the box inside each x word.
            const uint64_t zBits = ((2u << hi[2][rz]) - 1) & ~((1u << lo[2][rz]) - 1);
            const uint64_t yBytes =
                (hi[1][ry] == 7 ? ~uint64_t{0} : (uint64_t{1} << (8 * (hi[1][ry] + 1))) - 1) &
                ~((uint64_t{1} << (8 * lo[1][ry])) - 1);
            const uint64_t box = zBits * 0x0101010101010101ull & yBytes;
            const LeafBits& bits = m_leafBits[leaf];
            for (int x = lo[0][rx]; x <= hi[0][rx]; ++x) {
                anyNeg |= (bits.negative[x] & box) != 0;
                anyPos |= (~bits.negative[x] & box) != 0;
                near |= (bits.near[x] & box) != 0;
            }
        }
        if (near || (anyNeg && anyPos)) return static_cast<uint8_t>(BlockFlag::Surface);
        return static_cast<uint8_t>(anyNeg ? BlockFlag::Inside : BlockFlag::Outside);
    }

    // Per worker: tile regions filled with their value, so that leaves and tiles read alike. Tile
    // values are mostly +-background: a few filled regions, each kept for its value.
    struct GatherScratch {
        static constexpr int kSlots = 4;
        std::vector<float> tileFill = std::vector<float>(kSlots * 512);
        float value[kSlots] = {NAN, NAN, NAN, NAN};
        int next = 0;  // the slot refilled next when no slot holds a value
        const float* region(float v) {
            for (int s = 0; s < kSlots; ++s)
                if (value[s] == v) return tileFill.data() + s * 512;
            float* fill = tileFill.data() + next * 512;
            std::fill(fill, fill + 512, v);
            value[next] = v;
            next = (next + 1) % kSlots;
            return fill;
        }
    };

    // Block b's (B+1)^3 samples into `out`, x fastest. Its V vertices per axis span at most two
    // 8-voxel regions: per axis, each vertex's region (0 or 1 from the first) and its offset inside
    // the leaf; per region of the 2x2x2, the leaf's values or a tile value repeated.
    void gatherBlock(const int b[3], float* out, GatherScratch& scratch, const TileRegions& tr,
                     LeafCache& leaves) const {
        const int V = m_V;
        int region[3][9], offset[3][9];  // V <= 9
        int first[3];
        for (int a = 0; a < 3; ++a) {
            first[a] = (m_lo[a] + b[a] * m_B) >> 3;
            for (int n = 0; n < V; ++n) {
                // Clamped to the grid as GridView::vertex clamps.
                const int32_t x = m_lo[a] + std::min(b[a] * m_B + n, m_shape.cells[a]);
                region[a][n] = (x >> 3) - first[a];
                offset[a][n] = (x & 7) << (a == 0 ? 6 : a == 1 ? 3 : 0);
            }
        }
        const float* source[8];
        for (int c = 0; c < 8; ++c) {
            const int32_t x = (first[0] + (c & 1)) * 8, y = (first[1] + (c >> 1 & 1)) * 8,
                          z = (first[2] + (c >> 2)) * 8;
            // Regions past the active region are never read (the vertices clamp).
            if (x > m_hi[0] || y > m_hi[1] || z > m_hi[2]) {
                source[c] = nullptr;
                continue;
            }
            float v = 0;
            const int32_t leaf = tr.at(x >> 3, y >> 3, z >> 3, v);
            source[c] = leaf >= 0 ? leaves.values(leaf) : scratch.region(v);
        }
        // x splits between the two regions at most once per row, at the same place in every row.
        int split = 0;
        while (split < V && region[0][split] == 0) ++split;
        for (int k = 0; k < V; ++k)
            for (int j = 0; j < V; ++j) {
                const int rjk = 2 * region[1][j] + 4 * region[2][k];
                const int ojk = offset[1][j] | offset[2][k];
                // (The offsets' bits are disjoint; a null source is never indexed.)
                const float* row0 = source[rjk];
                const float* row1 = source[rjk + 1];
                for (int i = 0; i < split; ++i) out[i] = row0[ojk | offset[0][i]];
                for (int i = split; i < V; ++i) out[i] = row1[ojk | offset[0][i]];
                out += V;
            }
    }

    // Pass 2: the surface blocks' samples, clamped to the band, into the grid's builder (every
    // vertex's value comes from the tree, so blocks that share one agree); own pages in parallel,
    // in the order of the first leaf each reads, so that the leaves are decoded in the file's
    // order, kept in each worker's cache while its next tiles read them, and their pages
    // released behind the tiles (the leaves are never all decoded at once).
    void sampleSurfaceBlocks(SparseGridBuilder& builder) const {
        const std::vector<int>& own = builder.ownTiles();
        const size_t pages = own.size() / 3;
        std::vector<std::pair<int32_t, uint32_t>> order(pages);  // (first leaf, page)
        tbb::parallel_for(size_t(0), pages, [&](size_t p) {
            TileRegions tr;
            tileRegions(&own[3 * p], tr);
            int32_t first = std::numeric_limits<int32_t>::max();
            for (int i = 0; i < tr.n[0] * tr.n[1] * tr.n[2]; ++i)
                if (tr.leaf[i] >= 0) first = std::min(first, tr.leaf[i]);
            order[p] = {first, static_cast<uint32_t>(p)};
        });
        std::sort(order.begin(), order.end());
        const size_t maxRegions = static_cast<size_t>(TileRegions::regionsPerTile(m_B));
        const size_t capacity = m_cachedLeaves ? std::max(m_cachedLeaves, maxRegions)
                                               : std::max<size_t>(1024, 2 * maxRegions);
        tbb::enumerable_thread_specific<LeafCache> caches([&] { return LeafCache(m_g, capacity); });
        const size_t batch = std::max<size_t>(32, pages / 128);
        size_t released = 0;  // leaves whose pages are released
        for (size_t b0 = 0; b0 < pages; b0 += batch) {
            const size_t b1 = std::min(pages, b0 + batch);
            tbb::parallel_for(b0, b1, [&](size_t o) {
                LeafCache& cache = caches.local();
                cache.makeRoom(maxRegions);
                sampleTile(builder, order[o].second, cache);
            });
            // No later tile reads a leaf before its own first one.
            const size_t next = b1 < pages ? std::min<size_t>(static_cast<size_t>(order[b1].first),
                                                              m_t.leaves.size())
                                           : m_t.leaves.size();
            if (next > released) {
                releaseLeaves(released, next);
                released = next;
            }
        }
    }

    // The surface blocks of own page p, gathered and added to the builder.
    void sampleTile(SparseGridBuilder& builder, size_t p, LeafCache& cache) const {
        const std::vector<int>& own = builder.ownTiles();
        const std::vector<int32_t>& index = builder.blockData();
        const size_t perBlock = static_cast<size_t>(m_V) * m_V * m_V;
        const float band = m_band;
        GatherScratch scratch;
        TileRegions tr;
        tileRegions(&own[3 * p], tr);
        const size_t base = (p + kFirstOwnPage) * kPageEntries;
        float block[9 * 9 * 9];  // (B+1)^3, B <= 8
        forEachBlockOfTile(m_blocks, own[3 * p], own[3 * p + 1], own[3 * p + 2],
                           [&](int bi, int bj, int bk) {
                               const int32_t at = index[base + pageLocal(bi, bj, bk)];
                               if (at < 0) return;
                               const int b[3] = {bi, bj, bk};
                               gatherBlock(b, block, scratch, tr, cache);
#pragma omp simd
                               for (size_t n = 0; n < perBlock; ++n) {
                                   const float v = block[n];
                                   block[n] = v < -band ? -band : (v > band ? band : v);
                               }
                               builder.addBlock(bi, bj, bk, block);
                           });
    }

    vdb::FloatGrid& m_g;
    const vdb::Tree& m_t;
    const std::string& m_path;
    const int m_B, m_V;
    const size_t m_cachedLeaves;
    std::array<int32_t, 3> m_lo{}, m_hi{};
    GridShape m_shape;
    float m_bandVoxels = 0, m_band = 0;
    float m_tileFloor = 0;  // tiles hold at least this magnitude (min(band, background))
    static constexpr int kUnitLog2 = 7;  // a lower internal node: 128 voxels
    int m_blocks[3] = {0, 0, 0}, m_tiles[3] = {0, 0, 0};
    size_t m_numTiles = 0;
    int32_t m_u0[3] = {0, 0, 0}, m_un[3] = {0, 0, 0};
    std::vector<int32_t> m_unitLower;
    std::vector<float> m_unitValue;
    std::vector<LeafBits> m_leafBits;
    std::string m_gridName;
};

}  // namespace

Grid loadVdb(const std::string& path, const VdbImportOptions& options) {
    return readWithinBudget(path, [&] {
        vdb::FloatGrid g = vdb::readVdbFile(path);
        return TreeToGrid(g, path, options).build();
    });
}

void saveVdb(const Grid& grid, const std::string& path) {
    // Encoded in memory by OpenVDB (its plugin), then written with every write checked.
    std::string bytes, error;
    if (!openVdbPlugin("writing " + path).encodeVdb(grid.view(), bytes, error))
        throw InputError(path + ": cannot write OpenVDB file (" + error + ")");
    writeFileAtomically(path, bytes.data(), bytes.size());
}

}  // namespace sdft
