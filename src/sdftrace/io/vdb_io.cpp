#include "sdftrace/io/vdb_io.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>

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
        std::vector<size_t> slabCandidates(m_blocks[2]);
        const size_t candidates = flagBlocks(flags, slabCandidates);

        checkMemoryBudget(
            m_numBlocks * 5.0 + 2.0 * m_V * m_V * m_V * sizeof(float) * candidates, m_path,
            "the samples of " + std::to_string(candidates) + " blocks near its surface",
            "resample the level set coarser");
        std::vector<float> samples = sampleCandidates(flags, slabCandidates, candidates);
        return Grid::sparseFromBuffers(m_shape, m_B, (m_bandVoxels - 1) * m_shape.voxelSize,
                                       std::move(flags), std::move(samples), m_path);
    }

  private:
    static constexpr uint8_t kCandidate = 3;

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
        for (const vdb::Leaf& leaf : m_t.leaves)
            for (float v : leaf.values)
                if (!std::isfinite(v))
                    throw InputError(m_path + ": non-finite values in grid '" + g.name + "'");
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

    // Pass 1, cheap: which blocks need their samples (they touch a leaf, or their tile corners
    // are near the surface or of both signs), the others flagged by their tile's sign. Tiles near
    // zero or a band wider than the level set's can make far more candidates than the leaves
    // suggest, so the caller checks their samples against the budget before any is computed.
    size_t flagBlocks(std::vector<uint8_t>& flags, std::vector<size_t>& slabCandidates) const {
        std::atomic<size_t> candidates{0};
        tbb::parallel_for(0, m_blocks[2], [&](int bk) {
            size_t count = 0;
            for (int bj = 0; bj < m_blocks[1]; ++bj)
                for (int bi = 0; bi < m_blocks[0]; ++bi) {
                    const int b[3] = {bi, bj, bk};
                    bool touches = false, anyNeg = false, anyPos = false, near = false;
                    for (int corner = 0; corner < 8; ++corner) {
                        int vtx[3];
                        for (int a = 0; a < 3; ++a) vtx[a] = b[a] * m_B + ((corner >> a) & 1) * m_B;
                        const auto [x, y, z] = voxel(vtx[0], vtx[1], vtx[2]);
                        touches |= m_regionLeaf[regionOf(x, y, z)] >= 0;
                        const float v = value(vtx[0], vtx[1], vtx[2]);
                        anyNeg |= v < 0;
                        anyPos |= v >= 0;
                        near |= std::fabs(v) < m_band;
                    }
                    uint8_t& flag = flags[blockIndex(bi, bj, bk)];
                    if (touches || near || (anyNeg && anyPos)) {
                        flag = kCandidate;
                        ++count;
                    } else {
                        flag =
                            static_cast<uint8_t>(anyNeg ? BlockFlag::Inside : BlockFlag::Outside);
                    }
                }
            slabCandidates[bk] = count;
            candidates += count;
        });
        return candidates.load();
    }

    // Per worker: tile regions filled with their value, so that leaves and tiles read alike.
    struct GatherScratch {
        std::vector<float> tileFill = std::vector<float>(8 * 512);
        float filled[8] = {NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN};
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
            // Tiles mostly hold the same +-background: refill only on a change.
            float* fill = scratch.tileFill.data() + c * 512;
            if (!(scratch.filled[c] == m_regionValue[r])) {
                std::fill(fill, fill + 512, m_regionValue[r]);
                scratch.filled[c] = m_regionValue[r];
            }
            source[c] = fill;
        }
        // x splits between the two regions at most once per row.
        for (int k = 0; k < V; ++k)
            for (int j = 0; j < V; ++j) {
                const int rjk = 2 * region[1][j] + 4 * region[2][k];
                const int ojk = offset[1][j] | offset[2][k];
                // (The offsets' bits are disjoint; a null source is never indexed.)
                const float* row0 = source[rjk];
                const float* row1 = source[rjk + 1];
                int i = 0;
                for (; i < V && region[0][i] == 0; ++i) *out++ = row0[ojk | offset[0][i]];
                for (; i < V; ++i) *out++ = row1[ojk | offset[0][i]];
            }
    }

    // Pass 2: the candidates' samples, in block order; a candidate whose samples are all far is
    // not a surface block after all.
    //
    // Each z-slab of blocks writes its surface blocks' samples in place, from where its first
    // candidate would go; the slabs are then moved together (one copy, no per-slab buffers).
    std::vector<float> sampleCandidates(std::vector<uint8_t>& flags,
                                        const std::vector<size_t>& slabCandidates,
                                        size_t candidates) const {
        const int V = m_V;
        const size_t perBlock = static_cast<size_t>(V) * V * V;
        std::vector<size_t> slabStart(m_blocks[2] + 1, 0), slabSurface(m_blocks[2], 0);
        for (int bk = 0; bk < m_blocks[2]; ++bk)
            slabStart[bk + 1] = slabStart[bk] + slabCandidates[bk];
        std::vector<float> samples;
        samples.reserve(candidates * perBlock);
        adviseHugePages(samples.data(), candidates * perBlock * sizeof(float));
        samples.resize(candidates * perBlock);
        tbb::parallel_for(0, m_blocks[2], [&](int bk) {
            size_t surface = 0;
            GatherScratch scratch;
            for (int bj = 0; bj < m_blocks[1]; ++bj)
                for (int bi = 0; bi < m_blocks[0]; ++bi) {
                    uint8_t& flag = flags[blockIndex(bi, bj, bk)];
                    if (flag != kCandidate) continue;
                    float* const block = samples.data() + (slabStart[bk] + surface) * perBlock;
                    const int b[3] = {bi, bj, bk};
                    gatherBlock(b, block, scratch);
                    // Clamped to the band and classified in one contiguous pass.
                    bool anyNeg = false, anyPos = false, near = false;
                    for (float* v = block; v != block + perBlock; ++v) {
                        *v = std::clamp(*v, -m_band, m_band);
                        anyNeg |= *v < 0;
                        anyPos |= *v >= 0;
                        near |= std::fabs(*v) < m_band;
                    }
                    if (near || (anyNeg && anyPos)) {
                        flag = static_cast<uint8_t>(BlockFlag::Surface);
                        ++surface;
                    } else {
                        flag =
                            static_cast<uint8_t>(anyNeg ? BlockFlag::Inside : BlockFlag::Outside);
                    }
                }
            slabSurface[bk] = surface;
        });
        size_t end = 0;
        for (int bk = 0; bk < m_blocks[2]; ++bk) {
            const size_t n = slabSurface[bk] * perBlock, from = slabStart[bk] * perBlock;
            if (from != end)
                std::memmove(samples.data() + end, samples.data() + from, n * sizeof(float));
            end += n;
        }
        samples.resize(end);
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
