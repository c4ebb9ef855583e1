#include "sdftrace/io/vdb_io.h"

#include <emmintrin.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "../field/openvdb_plugin.h"
#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/io/atomic_file.h"
#include "vdb_reader.h"

namespace sdft {

namespace {

// The active voxels' index bounds (leaves' value masks, active tiles); false if none.
bool activeBounds(const vdb::Tree& t, std::array<int32_t, 3>& lo, std::array<int32_t, 3>& hi) {
    bool any = false;
    auto include = [&](int32_t x, int32_t y, int32_t z, int32_t extent) {
        const int32_t p[3] = {x, y, z};
        for (int a = 0; a < 3; ++a) {
            lo[a] = any ? std::min(lo[a], p[a]) : p[a];
            hi[a] = any ? std::max(hi[a], p[a] + extent - 1) : p[a] + extent - 1;
        }
        any = true;
    };
    // A leaf's mask word w holds x = w; its bit b holds y = b >> 3, z = b & 7.
    for (const vdb::Leaf& leaf : t.leaves) {
        uint64_t any = 0;
        int x0 = 8, x1 = -1;
        for (int w = 0; w < 8; ++w) {
            if (!leaf.active[w]) continue;
            any |= leaf.active[w];
            x0 = std::min(x0, w);
            x1 = w;
        }
        if (!any) continue;
        uint8_t rows = 0, cols = 0;  // y and z present
        for (uint64_t bits = any; bits; bits &= bits - 1) {
            const int b = std::countr_zero(bits);
            rows |= static_cast<uint8_t>(1u << (b >> 3));
            cols |= static_cast<uint8_t>(1u << (b & 7));
        }
        const int y0 = std::countr_zero(rows), y1 = 7 - std::countl_zero(rows);
        const int z0 = std::countr_zero(cols), z1 = 7 - std::countl_zero(cols);
        include(leaf.origin[0] + x0, leaf.origin[1] + y0, leaf.origin[2] + z0, 1);
        include(leaf.origin[0] + x1, leaf.origin[1] + y1, leaf.origin[2] + z1, 1);
    }
    for (const vdb::RootTile& tile : t.tiles)
        if (tile.active) include(tile.origin[0], tile.origin[1], tile.origin[2], 4096);
    auto tiles = [&](const std::vector<vdb::Internal>& nodes, int log2, int shift) {
        for (const vdb::Internal& n : nodes)
            for (int i = 0; i < (1 << (3 * log2)); ++i)
                if (((n.valueMask[i >> 6] >> (i & 63)) & 1u) && n.children[i] < 0)
                    include(n.origin[0] + ((i >> (2 * log2)) << shift),
                            n.origin[1] + (((i >> log2) & ((1 << log2) - 1)) << shift),
                            n.origin[2] + ((i & ((1 << log2) - 1)) << shift), 1 << shift);
    };
    tiles(t.upper, 5, 7);
    tiles(t.lower, 4, 3);
    return any;
}

// The tree straight into a sparse block grid: blocks that touch a leaf (or whose corners are near
// or of both signs) get their samples from the tree; every other block lies in one tile region
// and takes its flag from the sign there. Same grid as sampling the dense active region and
// sparsifying it (Grid::sparseFromDense), without the dense array.
class TreeToGrid {
  public:
    TreeToGrid(const vdb::FloatGrid& g, const std::string& path, const VdbImportOptions& o)
        : m_t(g.tree), m_path(path), m_B(o.blockSize), m_V(o.blockSize + 1) {
        if (!activeBounds(m_t, m_lo, m_hi))
            throw InputError(path + ": grid '" + g.name + "' has no active voxels");
        makeShape(g);
        const float h = m_shape.voxelSize;
        m_bandVoxels = std::max(o.minBandVoxels, std::fabs(m_t.background) / h * 0.999f);
        m_band = m_bandVoxels * h;
        for (int a = 0; a < 3; ++a) m_blocks[a] = (m_shape.cells[a] + m_B - 1) / m_B;
        m_numBlocks = static_cast<size_t>(m_blocks[0]) * m_blocks[1] * m_blocks[2];
        checkMemoryBudget(
            static_cast<double>(m_numBlocks) * 5 +
                static_cast<double>(m_t.leaves.size()) * 8 * m_V * m_V * m_V * sizeof(float),
            path, "the sparse grid's block tables and surface blocks",
            "resample the level set coarser");
        indexRegions();
    }

    Grid build() {
        std::vector<uint8_t> flags(m_numBlocks);
        std::vector<size_t> slabSurface(m_blocks[2]);
        computeLeafBits();
        const size_t surface = flagBlocks(flags, slabSurface);

        checkMemoryBudget(
            m_numBlocks * 5.0 + m_V * m_V * m_V * sizeof(float) * static_cast<double>(surface),
            m_path, "the samples of " + std::to_string(surface) + " blocks near its surface",
            "resample the level set coarser");
        std::vector<float> samples = sampleSurfaceBlocks(flags, slabSurface, surface);
        return Grid::sparseFromBuffers(m_shape, m_B, (m_bandVoxels - 1) * m_shape.voxelSize,
                                       std::move(flags), std::move(samples), m_path);
    }

  private:
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
        m_gridName = g.name;
    }

    // The active region in 8^3-voxel regions on the VDB leaf grid: per region its leaf (or -1)
    // and otherwise its tile value, so that a sample is two array reads, not a tree descent.
    void indexRegions() {
        for (int a = 0; a < 3; ++a) {
            m_r0[a] = m_lo[a] >> 3;
            m_rn[a] = (m_hi[a] >> 3) - m_r0[a] + 1;
        }
        const size_t numRegions = static_cast<size_t>(m_rn[0]) * m_rn[1] * m_rn[2];
        checkMemoryBudget(
            static_cast<double>(numRegions) * 8, m_path,
            "an index of the active region's " + std::to_string(numRegions) + " leaf-sized regions",
            "resample the level set coarser");
        m_regionLeaf.assign(numRegions, -1);
        m_regionValue.resize(numRegions);
        tbb::parallel_for(0, m_rn[2], [&](int rz) {
            for (int ry = 0; ry < m_rn[1]; ++ry)
                for (int rx = 0; rx < m_rn[0]; ++rx) {
                    const int32_t x = (m_r0[0] + rx) * 8, y = (m_r0[1] + ry) * 8,
                                  z = (m_r0[2] + rz) * 8;
                    m_regionValue[regionOf(x, y, z)] = m_t.value(x, y, z);
                }
        });
        for (size_t i = 0; i < m_t.leaves.size(); ++i) {
            const auto& o = m_t.leaves[i].origin;
            bool inside = true;
            for (int a = 0; a < 3; ++a)
                inside = inside && o[a] >= m_r0[a] * 8 && o[a] < (m_r0[a] + m_rn[a]) * 8;
            if (inside) m_regionLeaf[regionOf(o[0], o[1], o[2])] = static_cast<int32_t>(i);
        }
    }

    size_t regionOf(int32_t x, int32_t y, int32_t z) const {
        return (static_cast<size_t>((z >> 3) - m_r0[2]) * m_rn[1] + ((y >> 3) - m_r0[1])) *
                   m_rn[0] +
               ((x >> 3) - m_r0[0]);
    }

    // Vertex (i, j, k), clamped to the grid as GridView::vertex clamps, is voxel lo + (i, j, k).
    std::array<int32_t, 3> voxel(int i, int j, int k) const {
        return {m_lo[0] + std::min(i, m_shape.cells[0]), m_lo[1] + std::min(j, m_shape.cells[1]),
                m_lo[2] + std::min(k, m_shape.cells[2])};
    }

    float value(int i, int j, int k) const {
        const auto [x, y, z] = voxel(i, j, k);
        const size_t r = regionOf(x, y, z);
        const int32_t leaf = m_regionLeaf[r];
        return leaf < 0 ? m_regionValue[r]
                        : m_t.leaves[leaf].values[((x & 7) << 6) | ((y & 7) << 3) | (z & 7)];
    }

    size_t blockIndex(int bi, int bj, int bk) const {
        return (static_cast<size_t>(bk) * m_blocks[1] + bj) * m_blocks[0] + bi;
    }

    // Pass 1: every block's flag. Blocks whose corners are far from a leaf, far from the surface
    // and of one sign take it from there; the others (candidates) are classified by their
    // samples' sign and band bits (classify), without gathering them. Returns the number of
    // surface blocks, per z-slab in `slabSurface`. Tiles near zero or a band wider than the level
    // set's can make far more surface blocks than the leaves suggest, so the caller checks their
    // samples against the budget before any is gathered.
    size_t flagBlocks(std::vector<uint8_t>& flags, std::vector<size_t>& slabSurface) const {
        // Block corners are shared by 8 blocks: each lattice vertex (a multiple of B) looked up
        // once, as bits: 1 its region holds a leaf, 2 negative, 4 within the band.
        const int lx = m_blocks[0] + 1, ly = m_blocks[1] + 1, lz = m_blocks[2] + 1;
        std::vector<uint8_t> corner(static_cast<size_t>(lx) * ly * lz);
        tbb::parallel_for(0, lz, [&](int ck) {
            for (int cj = 0; cj < ly; ++cj)
                for (int ci = 0; ci < lx; ++ci) {
                    const int i = ci * m_B, j = cj * m_B, k = ck * m_B;
                    const auto [x, y, z] = voxel(i, j, k);
                    const float v = value(i, j, k);
                    corner[(static_cast<size_t>(ck) * ly + cj) * lx + ci] =
                        static_cast<uint8_t>((m_regionLeaf[regionOf(x, y, z)] >= 0 ? 1 : 0) |
                                             (v < 0 ? 2 : 0) | (std::fabs(v) < m_band ? 4 : 0));
                }
        });
        std::atomic<size_t> surface{0};
        tbb::parallel_for(0, m_blocks[2], [&](int bk) {
            size_t count = 0;
            for (int bj = 0; bj < m_blocks[1]; ++bj)
                for (int bi = 0; bi < m_blocks[0]; ++bi) {
                    uint8_t any = 0, all = 0xff;
                    for (int c = 0; c < 8; ++c) {
                        const uint8_t bits =
                            corner[(static_cast<size_t>(bk + (c >> 2)) * ly + bj + (c >> 1 & 1)) *
                                       lx +
                                   bi + (c & 1)];
                        any |= bits;
                        all &= bits;
                    }
                    const bool touches = any & 1, anyNeg = any & 2, anyPos = !(all & 2),
                               near = any & 4;
                    uint8_t& flag = flags[blockIndex(bi, bj, bk)];
                    if (touches || near || (anyNeg && anyPos)) {
                        const int b[3] = {bi, bj, bk};
                        flag = classify(b);
                        count += flag == static_cast<uint8_t>(BlockFlag::Surface);
                    } else {
                        flag =
                            static_cast<uint8_t>(anyNeg ? BlockFlag::Inside : BlockFlag::Outside);
                    }
                }
            slabSurface[bk] = count;
            surface += count;
        });
        return surface.load();
    }

    // Per leaf, one bit per voxel (word x, bit y << 3 | z, as the leaf stores them): negative,
    // and within the band.
    struct LeafBits {
        uint64_t negative[8], near[8];
    };

    // Also refuses non-finite values (|v| <= FLT_MAX fails for them).
    void computeLeafBits() {
        m_leafBits.resize(m_t.leaves.size());
        std::atomic<bool> finite{true};
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, m_t.leaves.size(), 256), [&](const auto& range) {
                const __m128 sign = _mm_set1_ps(-0.0f), zero = _mm_setzero_ps(),
                             band = _mm_set1_ps(m_band),
                             largest = _mm_set1_ps(std::numeric_limits<float>::max());
                int allFinite = 0xf;
                for (size_t l = range.begin(); l != range.end(); ++l) {
                    const float* v = m_t.leaves[l].values.data();
                    LeafBits& bits = m_leafBits[l];
                    for (int x = 0; x < 8; ++x) {
                        uint64_t negative = 0, near = 0;
                        for (int q = 0; q < 16; ++q) {
                            const __m128 f = _mm_loadu_ps(v + x * 64 + q * 4);
                            const __m128 magnitude = _mm_andnot_ps(sign, f);
                            negative |= uint64_t(_mm_movemask_ps(_mm_cmplt_ps(f, zero))) << (4 * q);
                            near |= uint64_t(_mm_movemask_ps(_mm_cmplt_ps(magnitude, band)))
                                    << (4 * q);
                            allFinite &= _mm_movemask_ps(_mm_cmple_ps(magnitude, largest));
                        }
                        bits.negative[x] = negative;
                        bits.near[x] = near;
                    }
                }
                if (allFinite != 0xf) finite = false;
            });
        if (!finite) throw InputError(m_path + ": non-finite values in grid '" + m_gridName + "'");
    }

    // Block b's flag from its (B+1)^3 samples' bits, without gathering them: surface if one is
    // within the band or their signs differ (as Grid::sparseFromDense decides), else inside or
    // outside by their sign. Its vertices per axis span at most two 8-voxel regions, a box in
    // each.
    uint8_t classify(const int b[3]) const {
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
            const size_t r =
                regionOf((first[0] + rx) * 8, (first[1] + ry) * 8, (first[2] + rz) * 8);
            const int32_t leaf = m_regionLeaf[r];
            if (leaf < 0) {
                const float v = m_regionValue[r];
                anyNeg |= v < 0;
                anyPos |= !(v < 0);
                near |= std::fabs(v) < m_band;
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
    void gatherBlock(const int b[3], float* out, GatherScratch& scratch) const {
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
            if ((x >> 3) - m_r0[0] >= m_rn[0] || (y >> 3) - m_r0[1] >= m_rn[1] ||
                (z >> 3) - m_r0[2] >= m_rn[2]) {
                source[c] = nullptr;
                continue;
            }
            const size_t r = regionOf(x, y, z);
            const int32_t leaf = m_regionLeaf[r];
            if (leaf >= 0) {
                source[c] = m_t.leaves[leaf].values.data();
                continue;
            }
            source[c] = scratch.region(m_regionValue[r]);
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

    // Pass 2: the surface blocks' samples, in block order, clamped to the band; each z-slab of
    // blocks writes from where its first surface block goes.
    std::vector<float> sampleSurfaceBlocks(const std::vector<uint8_t>& flags,
                                           const std::vector<size_t>& slabSurface,
                                           size_t surface) const {
        const int V = m_V;
        const size_t perBlock = static_cast<size_t>(V) * V * V;
        std::vector<size_t> slabStart(m_blocks[2] + 1, 0);
        for (int bk = 0; bk < m_blocks[2]; ++bk)
            slabStart[bk + 1] = slabStart[bk] + slabSurface[bk];
        std::vector<float> samples;
        samples.reserve(surface * perBlock);
        adviseHugePages(samples.data(), surface * perBlock * sizeof(float));
        samples.resize(surface * perBlock);
        const float band = m_band;
        tbb::parallel_for(0, m_blocks[2], [&](int bk) {
            float* block = samples.data() + slabStart[bk] * perBlock;
            GatherScratch scratch;
            for (int bj = 0; bj < m_blocks[1]; ++bj)
                for (int bi = 0; bi < m_blocks[0]; ++bi) {
                    if (flags[blockIndex(bi, bj, bk)] != static_cast<uint8_t>(BlockFlag::Surface))
                        continue;
                    const int b[3] = {bi, bj, bk};
                    gatherBlock(b, block, scratch);
                    for (size_t n = 0; n < perBlock; ++n)
                        block[n] = std::min(std::max(block[n], -band), band);
                    block += perBlock;
                }
        });
        return samples;
    }

    const vdb::Tree& m_t;
    const std::string& m_path;
    const int m_B, m_V;
    std::array<int32_t, 3> m_lo{}, m_hi{};
    GridShape m_shape;
    float m_bandVoxels = 0, m_band = 0;
    int m_blocks[3] = {0, 0, 0};
    size_t m_numBlocks = 0;
    int32_t m_r0[3] = {0, 0, 0}, m_rn[3] = {0, 0, 0};
    std::vector<int32_t> m_regionLeaf;
    std::vector<float> m_regionValue;
    std::vector<LeafBits> m_leafBits;
    std::string m_gridName;
};

}  // namespace

Grid loadVdb(const std::string& path, const VdbImportOptions& options) {
    const vdb::FloatGrid g = vdb::readVdbFile(path);
    return TreeToGrid(g, path, options).build();
}

void saveVdb(const Grid& grid, const std::string& path) {
    // Encoded in memory by OpenVDB (its plugin), then written with every write checked.
    std::string bytes, error;
    if (!openVdbPlugin("writing " + path).encodeVdb(grid.view(), bytes, error))
        throw InputError(path + ": cannot write OpenVDB file (" + error + ")");
    writeFileAtomically(path, bytes.data(), bytes.size());
}

}  // namespace sdft
