#include "sdftrace/field/grid.h"

#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>

#include "block_apron_layout.h"
#include "sdftrace/core/error.h"
#include "sdftrace/core/macros.h"
#include "sdftrace/field/sparse_grid_builder.h"

namespace sdft {

namespace {
bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }
}  // namespace

Grid Grid::dense(const GridShape& shape, std::vector<float> samples) {
    SDFT_CHECK(samples.size() == shape.vertexCount());
    Grid g;
    g.m_kind = GridKind::Dense;
    g.m_shape = shape;
    g.m_samples = std::move(samples);
    g.computeLipschitz();
    return g;
}

std::vector<float> Grid::vertexSamples() const {
    if (m_kind == GridKind::Dense) return m_samples;
    const GridView v = view();
    std::vector<float> out(m_shape.vertexCount());
    size_t n = 0;
    for (int k = 0; k <= m_shape.cells[2]; ++k)
        for (int j = 0; j <= m_shape.cells[1]; ++j)
            for (int i = 0; i <= m_shape.cells[0]; ++i) out[n++] = v.vertex(i, j, k);
    return out;
}

Grid Grid::sparseFromDense(const GridShape& shape, const std::vector<float>& samples, int B,
                           float bandVoxels) {
    SDFT_CHECK(samples.size() == shape.vertexCount());
    SDFT_CHECK(B == 4 || B == 8);  // GridView::blockShift
    SDFT_CHECK(bandVoxels >= 2);
    int blocks[3];
    for (int a = 0; a < 3; ++a) blocks[a] = (shape.cells[a] + B - 1) / B;
    const float band = bandVoxels * shape.voxelSize;
    const size_t numBlocks = static_cast<size_t>(blocks[0]) * blocks[1] * blocks[2];
    const int V = B + 1;
    const size_t per = static_cast<size_t>(V) * V * V;
    const size_t vx = static_cast<size_t>(shape.cells[0]) + 1,
                 vy = static_cast<size_t>(shape.cells[1]) + 1;
    // Block (bi, bj, bk)'s (B+1)^3 vertex indices into `samples`, clamped to the grid (blocks at
    // the far faces reach past it) as GridView::vertex clamps.
    auto blockIndices = [&](int bi, int bj, int bk, size_t* out) {
        int c[3][9];
        const int b[3] = {bi, bj, bk};
        for (int a = 0; a < 3; ++a)
            for (int i = 0; i < V; ++i) c[a][i] = std::min(b[a] * B + i, shape.cells[a]);
        for (int k = 0; k < V; ++k)
            for (int j = 0; j < V; ++j)
                for (int i = 0; i < V; ++i)
                    *out++ =
                        (static_cast<size_t>(c[2][k]) * vy + static_cast<size_t>(c[1][j])) * vx +
                        static_cast<size_t>(c[0][i]);
    };
    // Clamped to the band, as a narrow-band level set stores them.
    auto clamped = [band](float v) { return v < 0 ? -std::fmin(-v, band) : std::fmin(v, band); };
    // Each block's flag, in parallel over rows of blocks; a block is a surface block at its first
    // sample within the band (RTSDF's per-frame grids keep every block: one read each).
    std::vector<uint8_t> flags(numBlocks, static_cast<uint8_t>(BlockFlag::Outside));
    tbb::parallel_for(0, blocks[1] * blocks[2], [&](int row) {
        const int bj = row % blocks[1], bk = row / blocks[1];
        std::vector<size_t> index(per);
        for (int bi = 0; bi < blocks[0]; ++bi) {
            blockIndices(bi, bj, bk, index.data());
            bool anyNeg = false, anyPos = false, near = false;
            for (size_t e = 0; e < per && !near; ++e) {
                const float v = clamped(samples[index[e]]);
                anyNeg |= v < 0;
                anyPos |= v >= 0;
                near |= std::fabs(v) < band;
            }
            const size_t block = (static_cast<size_t>(bk) * blocks[1] + bj) * blocks[0] + bi;
            flags[block] = static_cast<uint8_t>(near || (anyNeg && anyPos) ? BlockFlag::Surface
                                                : anyNeg                   ? BlockFlag::Inside
                                                                           : BlockFlag::Outside);
        }
    });
    // The surface blocks' samples in block order, copied in parallel.
    std::vector<size_t> surface;
    for (size_t b = 0; b < numBlocks; ++b)
        if (flags[b] == static_cast<uint8_t>(BlockFlag::Surface)) surface.push_back(b);
    std::vector<float> blockSamples(surface.size() * per);
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, surface.size()), [&](const tbb::blocked_range<size_t>& r) {
            std::vector<size_t> index(per);
            for (size_t d = r.begin(); d != r.end(); ++d) {
                const size_t block = surface[d];
                blockIndices(static_cast<int>(block % blocks[0]),
                             static_cast<int>(block / blocks[0] % blocks[1]),
                             static_cast<int>(block / blocks[0] / blocks[1]), index.data());
                float* out = blockSamples.data() + d * per;
                for (size_t e = 0; e < per; ++e) out[e] = clamped(samples[index[e]]);
            }
        });
    // Samples of non-surface blocks are all at least band voxels from the surface; a point in such
    // a block is within half a cell diagonal (< 1 voxel) of one, so (band - 1) voxels is a lower
    // bound of its distance.
    return sparseFromBuffers(shape, B, (bandVoxels - 1) * shape.voxelSize, flags,
                             std::move(blockSamples), "dense samples");
}

Grid Grid::sparseFromBuffers(const GridShape& shape, int B, float background,
                             const std::vector<uint8_t>& flags, std::vector<float> blockSamples,
                             const std::string& source) {
    int blocks[3];
    for (int a = 0; a < 3; ++a) blocks[a] = (shape.cells[a] + B - 1) / B;
    return sparseFromTable(shape, B, background, BlockTable::fromDense(blocks, flags, source),
                           std::move(blockSamples), source);
}

Grid Grid::sparseFromTable(const GridShape& shape, int B, float background, BlockTable table,
                           std::vector<float> blockSamples, const std::string& source) {
    SparseGridBuilder builder(shape, B, background, std::move(table), source);
    const size_t surface = builder.surfaceBlocks();
    const int V = B + 1;
    const size_t per = static_cast<size_t>(V) * V * V;
    if (blockSamples.size() != surface * per) {
        throw InputError(source + ": " + std::to_string(surface) + " surface blocks need " +
                         std::to_string(surface * per) + " samples, the file has " +
                         std::to_string(blockSamples.size()));
    }
    // Samples from a file or a caller may disagree with their owners where two blocks share a
    // vertex: those entries stay private to the block (every cell reads what it was given).
    const ApronLayout L(B);
    builder.forEachSurfaceBlock([&](int bi, int bj, int bk, int32_t d) {
        const float* mine = blockSamples.data() + static_cast<size_t>(d) * per;
        uint8_t privateEntries = 0;
        for (int code = 1; code < 8; ++code) {
            const int32_t od = builder.neighbourData(bi, bj, bk, code);
            if (od < 0) continue;
            const float* theirs = blockSamples.data() + static_cast<size_t>(od) * per;
            for (const auto& v : L.byCode[code])
                if (!sameBits(mine[v.expanded], theirs[v.ownerExpanded])) {
                    privateEntries |= static_cast<uint8_t>(1u << code);
                    break;
                }
        }
        builder.addBlock(bi, bj, bk, mine, privateEntries);
    });
    blockSamples = std::vector<float>();
    return builder.finish();
}

namespace {
// Surface block `data`'s (B+1)^3 vertices (x fastest) of a per-stored-sample channel of `comps`
// floats (samples: 1, texture coordinates: 3), through the neighbour entries.
void expandChannel(const GridView& v, const float* channel, int comps, int32_t data, float* out) {
    const int B = v.blockSize, V = B + 1;
    for (int z = 0; z <= B; ++z)
        for (int y = 0; y <= B; ++y)
            for (int x = 0; x <= B; ++x) {
                const float* from = channel + comps * v.blockSampleIndex(data, x, y, z);
                std::copy(from, from + comps, out + comps * ((z * V + y) * V + x));
            }
}

// The channel expanded for every surface block, in parallel.
std::vector<float> expandAll(const GridView& v, size_t surfaceBlocks, const float* channel,
                             int comps) {
    const size_t per =
        static_cast<size_t>(comps) * (v.blockSize + 1) * (v.blockSize + 1) * (v.blockSize + 1);
    std::vector<float> out(surfaceBlocks * per);
    tbb::parallel_for(size_t(0), surfaceBlocks, [&](size_t s) {
        expandChannel(v, channel, comps, static_cast<int32_t>(s), out.data() + s * per);
    });
    return out;
}
}  // namespace

void Grid::expandBlock(int32_t data, float* out) const {
    expandChannel(view(), m_blockSamples.data(), 1, data, out);
}

std::vector<float> Grid::expandedBlockSamples() const {
    if (m_kind != GridKind::Sparse) return {};
    return expandAll(view(), m_surfaceBlocks, m_blockSamples.data(), 1);
}

std::vector<float> Grid::expandedTexcoords() const {
    if (m_texcoords.empty()) return {};
    if (m_kind == GridKind::Dense) return m_texcoords;
    return expandAll(view(), m_surfaceBlocks, m_texcoords.data(), 3);
}

void Grid::forEachStoredSample(const std::function<void(size_t, int32_t, int, int, int)>& f) const {
    SDFT_CHECK(m_kind == GridKind::Sparse);
    const int B = m_blockSize;
    const size_t own = static_cast<size_t>(B) * B * B;
    tbb::parallel_for(size_t(0), m_surfaceBlocks, [&](size_t s) {
        for (int z = 0; z < B; ++z)
            for (int y = 0; y < B; ++y)
                for (int x = 0; x < B; ++x)
                    f(s * own + static_cast<size_t>((z * B + y) * B + x), static_cast<int32_t>(s),
                      x, y, z);
    });
    const ApronLayout L(B);
    tbb::parallel_for(size_t(0), m_apronFrom.size(), [&](size_t e) {
        const int32_t s = m_apronFrom[e];
        if (s < 0) return;  // a shared constant block: no vertex of its own
        const size_t base = (m_surfaceBlocks + e) * own;
        for (const auto& v : L.byCode[m_apronCode[e]])
            f(base + static_cast<size_t>(v.ownerOwn), s, v.x, v.y, v.z);
    });
}

void Grid::setExpandedTexcoords(TexcoordKind kind, const std::vector<float>& texcoords,
                                const std::string& source) {
    if (m_kind == GridKind::Dense || kind == TexcoordKind::None) {
        setTexcoords(kind, texcoords, source);
        return;
    }
    const int V = m_blockSize + 1;
    const size_t per = static_cast<size_t>(V) * V * V;
    if (texcoords.size() != 3 * m_surfaceBlocks * per) {
        throw InputError(source + ": " + std::to_string(texcoords.size()) +
                         " texture-coordinate values for " + std::to_string(m_surfaceBlocks * per) +
                         " samples; expected 3 per sample");
    }
    std::vector<float> compact(3 * storedSamples(), 0.0f);
    forEachStoredSample([&](size_t sample, int32_t block, int x, int y, int z) {
        const float* t = texcoords.data() + 3 * (static_cast<size_t>(block) * per +
                                                 static_cast<size_t>((z * V + y) * V + x));
        compact[3 * sample] = t[0], compact[3 * sample + 1] = t[1], compact[3 * sample + 2] = t[2];
    });
    setTexcoords(kind, std::move(compact), source);
}

std::vector<uint8_t> Grid::denseFlags() const {
    SDFT_CHECK(m_kind == GridKind::Sparse);
    // The table's own expansion, on a copy of the tables (far smaller than the flat result).
    BlockTable t;
    for (int a = 0; a < 3; ++a) {
        t.blocks[a] = m_blocks[a];
        t.tiles[a] = m_tiles[a];
    }
    t.tilePage = m_tilePage;
    t.flags = m_flags;
    return t.dense();
}

void Grid::forEachPagedBlock(const std::function<void(int, int, int, size_t)>& f,
                             bool parallel) const {
    auto page = [&](size_t p) {
        const int* t = m_ownTiles.data() + 3 * p;
        const size_t base = (p + kFirstOwnPage) * kPageEntries;
        forEachBlockOfTile(m_blocks, t[0], t[1], t[2], [&](int bi, int bj, int bk) {
            f(bi, bj, bk, base + pageLocal(bi, bj, bk));
        });
    };
    const size_t pages = m_ownTiles.size() / 3;
    if (parallel)
        tbb::parallel_for(size_t(0), pages, page);
    else
        for (size_t p = 0; p < pages; ++p) page(p);
}

GridView Grid::view() const {
    GridView v;
    v.kind = m_kind;
    v.shape = m_shape;
    v.lipschitz = m_lipschitz;
    v.samples = m_samples.data();
    v.blockSize = m_blockSize;
    for (int a = 0; a < 3; ++a) {
        v.blocks[a] = m_blocks[a];
        v.tiles[a] = m_tiles[a];
    }
    v.tilePage = m_tilePage.data();
    v.tileSkip = m_tileSkip.empty() ? nullptr : m_tileSkip.data();
    v.tileLipschitz = m_tileLipschitz.empty() ? nullptr : m_tileLipschitz.data();
    v.blockLipschitz = m_blockLipschitz.empty() ? nullptr : m_blockLipschitz.data();
    v.lipschitzLevel[0] = m_lipschitz;
    v.lipschitzLevel[1] = m_gentleLipschitz;
    v.flags = m_flags.data();
    v.blockData = m_blockData.data();
    v.blockSamples = m_blockSamples.data();
    v.blockNeighbors = m_blockNeighbors.data();
    v.cellMasks = m_cellMasks.data();
    v.blockSkip = m_blockSkip.empty() ? nullptr : m_blockSkip.data();
    v.background = m_background;
    if (!m_gapLattice.empty()) {
        v.gapLattice = m_gapLattice.data();
        for (int a = 0; a < 3; ++a) v.gapCounts[a] = m_gapCounts[a];
        v.gapStep = m_gapStep;
        v.gapUnit = m_gapUnit;
    }
    if (!m_texcoords.empty()) {
        v.texcoords = m_texcoords.data();
        v.texcoordKind = static_cast<int>(m_texcoordKind);
    }
    return v;
}

void Grid::setTexcoords(TexcoordKind kind, std::vector<float> texcoords,
                        const std::string& source) {
    if (kind == TexcoordKind::None) {
        m_texcoords.clear();
        m_texcoordKind = kind;
        return;
    }
    if (texcoords.size() != 3 * storedSamples()) {
        throw InputError(source + ": " + std::to_string(texcoords.size()) +
                         " texture-coordinate values for " + std::to_string(storedSamples()) +
                         " samples; expected 3 per sample");
    }
    for (float t : texcoords)
        if (!std::isfinite(t)) throw InputError(source + ": non-finite texture coordinate");
    if (m_kind == GridKind::Sparse) {
        // Samples that stand for no vertex (the shared constant blocks, the unread part of
        // private apron blocks) carry zero vectors, as loaded files give them.
        std::vector<float> kept(texcoords.size(), 0.0f);
        forEachStoredSample([&](size_t sample, int32_t, int, int, int) {
            std::copy_n(texcoords.begin() + static_cast<ptrdiff_t>(3 * sample), 3,
                        kept.begin() + static_cast<ptrdiff_t>(3 * sample));
        });
        texcoords = std::move(kept);
    }
    m_texcoords = std::move(texcoords);
    m_texcoordKind = kind;
}

namespace {
// Calls f(i, j, k, corners) for every cell of a dense grid, in parallel by z slabs.
template <class F>
void forEachCell(const GridView& v, F&& f) {
    SDFT_CHECK(v.kind == GridKind::Dense);
    tbb::parallel_for(0, v.shape.cells[2], [&](int k) {
        for (int j = 0; j < v.shape.cells[1]; ++j)
            for (int i = 0; i < v.shape.cells[0]; ++i) {
                float c[8];
                v.cellCorners(i, j, k, c);
                f(i, j, k, c);
            }
    });
}
}  // namespace

Bounds3 Grid::surfaceBounds() const {
    tbb::combinable<Bounds3> perThread;
    const float h = m_shape.voxelSize;
    if (m_kind == GridKind::Sparse) {
        // The cell masks hold exactly the cells with a sign change (other blocks are constant).
        const int B = m_blockSize, words = (B * B * B + 63) / 64;
        forEachPagedBlock([&](int bi, int bj, int bk, size_t slot) {
            const int32_t data = m_blockData[slot];
            if (data < 0) return;
            const uint64_t* mask = m_cellMasks.data() + static_cast<size_t>(data) * words;
            int lo[3] = {B, B, B}, hi[3] = {-1, -1, -1};
            for (int w = 0; w < words; ++w)
                for (uint64_t bits = mask[w]; bits; bits &= bits - 1) {
                    const int bit = w * 64 + std::countr_zero(bits);
                    const int c[3] = {bit % B, (bit / B) % B, bit / (B * B)};
                    for (int a = 0; a < 3; ++a) {
                        lo[a] = std::min(lo[a], c[a]);
                        hi[a] = std::max(hi[a], c[a]);
                    }
                }
            if (hi[0] < 0) return;
            const Vec3 cell0(static_cast<float>(bi * B), static_cast<float>(bj * B),
                             static_cast<float>(bk * B));
            Bounds3& out = perThread.local();
            out.include(m_shape.origin + (cell0 + Vec3(lo[0], lo[1], lo[2])) * h);
            out.include(m_shape.origin + (cell0 + Vec3(hi[0] + 1, hi[1] + 1, hi[2] + 1)) * h);
        });
    } else {
        forEachCell(view(), [&](int i, int j, int k, const float c[8]) {
            if (!cornersChangeSign(c)) return;
            Vec3 lo = m_shape.origin + Vec3(i, j, k) * h;
            Bounds3& b = perThread.local();
            b.include(lo);
            b.include(lo + Vec3(h));
        });
    }
    Bounds3 b;
    perThread.combine_each([&](const Bounds3& t) {
        if (!t.empty()) {
            b.include(t.lo);
            b.include(t.hi);
        }
    });
    return b;
}

size_t Grid::memoryBytes() const {
    return m_samples.size() * sizeof(float) + m_flags.size() +
           m_blockData.size() * sizeof(int32_t) + m_blockSamples.size() * sizeof(float) +
           m_blockNeighbors.size() * sizeof(int32_t) + m_apronFrom.size() * sizeof(int32_t) +
           m_apronCode.size() + m_cellMasks.size() * sizeof(uint64_t) + m_blockSkip.size() +
           m_tilePage.size() * sizeof(int32_t) + m_tileSkip.size() + m_tileLipschitz.size() +
           m_blockLipschitz.size() + m_ownTiles.size() * sizeof(int) + m_gapLattice.size();
}

void Grid::blockCounts(size_t& inside, size_t& outside, size_t& surface) const {
    inside = outside = surface = 0;
    if (m_kind != GridKind::Sparse) return;
    const BlockCounts n = countBlocks(m_blocks, m_tiles, m_tilePage, m_flags);
    inside = n.inside;
    outside = n.outside;
    surface = n.surface;
}

size_t Grid::sparseMemoryEstimate(const BlockTable& t, size_t surface, int B) {
    const size_t slots = t.flags.size(), tiles = t.tilePage.size();
    const size_t ownPages = slots / kPageEntries - kFirstOwnPage;
    const size_t own = static_cast<size_t>(B) * B * B;
    // The terms of memoryBytes() as the builder sizes them, less the shared apron blocks.
    return surface * own * sizeof(float) + slots * (1 + sizeof(int32_t) + 1 + 1) +
           surface * (8 * sizeof(int32_t) + (own + 63) / 64 * sizeof(uint64_t)) +
           tiles * (sizeof(int32_t) + 1 + 1) + ownPages * 3 * sizeof(int);
}

namespace {
// The squared bound of the trilinear interpolant's gradient in a cell, times h^2: its derivative
// along x is a bilinear blend of the cell's 4 x-edge differences, so |df/dx| <= max |edge
// difference| / h, and likewise for y and z.
float cellGradientBound2(const float c[8]) {
    float gx = std::max({std::fabs(c[1] - c[0]), std::fabs(c[3] - c[2]), std::fabs(c[5] - c[4]),
                         std::fabs(c[7] - c[6])});
    float gy = std::max({std::fabs(c[2] - c[0]), std::fabs(c[3] - c[1]), std::fabs(c[6] - c[4]),
                         std::fabs(c[7] - c[5])});
    float gz = std::max({std::fabs(c[4] - c[0]), std::fabs(c[5] - c[1]), std::fabs(c[6] - c[2]),
                         std::fabs(c[7] - c[3])});
    return gx * gx + gy * gy + gz * gz;
}

}  // namespace

// Dense grids: the same Lipschitz bound over every cell (no masks: the DDA tracer reads sparse
// grids only).
void Grid::computeLipschitz() {
    tbb::combinable<float> worstPerThread([] { return 0.0f; });
    forEachCell(view(), [&](int, int, int, const float c[8]) {
        float& worst = worstPerThread.local();
        worst = std::max(worst, cellGradientBound2(c));
    });
    float worst = worstPerThread.combine([](float a, float b) { return std::max(a, b); });
    m_lipschitz = std::max(1.0f, std::sqrt(worst) / m_shape.voxelSize);
}

namespace {
// Chebyshev distance transform in place over an nx x ny x nz array (x fastest): entries start at
// 0 (a source) or kFar, and end at the distance to the nearest source, by a two-pass chamfer
// transform over the 26-neighbourhood (exact for this metric). Row by row: the 12 neighbours in
// the 4 rows already done are a minimum across the row (vectorized), then the one before it in
// the row is a sweep.
void chebyshevTransform(std::vector<uint16_t>& d, int nx, int ny, int nz, uint16_t far) {
    std::vector<uint16_t> fromRows(nx);
    auto pass = [&](int s) {
        for (int kk = 0; kk < nz; ++kk)
            for (int jj = 0; jj < ny; ++jj) {
                const int k = s > 0 ? kk : nz - 1 - kk, j = s > 0 ? jj : ny - 1 - jj;
                uint16_t* row = d.data() + (static_cast<size_t>(k) * ny + j) * nx;
                std::fill(fromRows.begin(), fromRows.end(), far);
                // Rows (j - s, k) and (j - 1..j + 1, k - s): done before this one.
                const int rows[4][2] = {{j - s, k}, {j - 1, k - s}, {j, k - s}, {j + 1, k - s}};
                for (const auto& [y, z] : rows) {
                    if (y < 0 || y >= ny || z < 0 || z >= nz) continue;
                    const uint16_t* r = d.data() + (static_cast<size_t>(z) * ny + y) * nx;
                    for (int i = 0; i < nx; ++i) {
                        const uint16_t left = i > 0 ? r[i - 1] : far;
                        const uint16_t right = i + 1 < nx ? r[i + 1] : far;
                        fromRows[i] = std::min({fromRows[i], left, r[i], right});
                    }
                }
                for (int i = 0; i < nx; ++i) row[i] = std::min<uint16_t>(row[i], fromRows[i] + 1);
                if (s > 0)
                    for (int i = 1; i < nx; ++i)
                        row[i] = std::min<uint16_t>(row[i], row[i - 1] + 1);
                else
                    for (int i = nx - 2; i >= 0; --i)
                        row[i] = std::min<uint16_t>(row[i], row[i + 1] + 1);
            }
    };
    pass(1);
    pass(-1);
}
}  // namespace

namespace {
// The Chebyshev distance (0 to 8) from each block of the centre tile of a 3^3-tile window to the
// window's set blocks (bit x of row win[z][y]) into out[local], by dilating the bits one block at a
// time; blocks farther than 8 keep their entry.
constexpr int kWindow = 3 * kTileBlocks;
void centreTileDistances(uint32_t (&win)[kWindow][kWindow], uint8_t* out) {
    constexpr int W = kWindow;
    constexpr uint32_t kRow = (1u << W) - 1;
    auto record = [&](int r, const uint32_t(&now)[W][W], const uint32_t(&before)[W][W]) {
        for (int z = 0; z < kTileBlocks; ++z)
            for (int y = 0; y < kTileBlocks; ++y) {
                const uint32_t fresh = (now[z + kTileBlocks][y + kTileBlocks] &
                                        ~before[z + kTileBlocks][y + kTileBlocks]) >>
                                       kTileBlocks;
                for (uint32_t bits = fresh & 0xffu; bits; bits &= bits - 1)
                    out[(z * kTileBlocks + y) * kTileBlocks + std::countr_zero(bits)] =
                        static_cast<uint8_t>(r);
            }
    };
    uint32_t none[W][W] = {};
    record(0, win, none);
    uint32_t prev[W][W];
    for (int r = 1; r <= kTileBlocks; ++r) {
        std::memcpy(prev, win, sizeof win);
        uint32_t tmp[W][W];
        for (int z = 0; z < W; ++z)
            for (int y = 0; y < W; ++y) {
                const uint32_t m = prev[z][y];
                tmp[z][y] = (m | m << 1 | m >> 1) & kRow;
            }
        uint32_t tmp2[W][W];
        for (int z = 0; z < W; ++z)
            for (int y = 0; y < W; ++y)
                tmp2[z][y] =
                    tmp[z][y] | (y > 0 ? tmp[z][y - 1] : 0) | (y + 1 < W ? tmp[z][y + 1] : 0);
        for (int z = 0; z < W; ++z)
            for (int y = 0; y < W; ++y)
                win[z][y] =
                    tmp2[z][y] | (z > 0 ? tmp2[z - 1][y] : 0) | (z + 1 < W ? tmp2[z + 1][y] : 0);
        record(r, win, prev);
    }
}
}  // namespace

// Empty-space skipping for the block DDA (not in the papers: Cohen & Sheffer's proximity clouds on
// Jamriška's block level, §4.1), on both levels of the table. Sources are the blocks holding a
// sign-changing cell: surface blocks of a narrow band whose cells all keep one sign (about half
// of them) are skipped like empty space, since no cell in them can be hit.
//  - tiles: the Chebyshev distance in tiles to the nearest tile holding a source (chamfer
//    transform over the tile grid, capped at 255);
//  - blocks of own pages: the distance in blocks to the nearest source, exact up to 8 and 9
//    beyond (a source within 8 blocks lies in the 3^3 tiles around the page): the page's window
//    of 24^3 blocks as bit rows, dilated by one block 8 times.
void Grid::computeBlockSkip() {
    const int words = (m_blockSize * m_blockSize * m_blockSize + 63) / 64;
    const size_t pages = m_ownTiles.size() / 3;
    // Per own page, its sources: one byte of x bits per (z, y) row.
    std::vector<uint8_t> rows(pages * kTileBlocks * kTileBlocks, 0);
    std::vector<uint8_t> pageHasSource(pages, 0);
    tbb::parallel_for(size_t(0), pages, [&](size_t p) {
        const size_t base = (p + kFirstOwnPage) * kPageEntries;
        uint8_t any = 0;
        for (int local = 0; local < kPageEntries; ++local) {
            const int32_t data = m_blockData[base + static_cast<size_t>(local)];
            if (data < 0) continue;
            const uint64_t* mask = m_cellMasks.data() + static_cast<size_t>(data) * words;
            bool crossing = false;
            for (int w = 0; w < words; ++w) crossing |= mask[w] != 0;
            if (crossing) {
                rows[p * 64 + static_cast<size_t>(local >> kTileShift)] |=
                    static_cast<uint8_t>(1u << (local & (kTileBlocks - 1)));
                any = 1;
            }
        }
        pageHasSource[p] = any;
    });

    constexpr uint16_t kFar = 256;
    std::vector<uint16_t> d(m_tilePage.size(), kFar);
    for (size_t tile = 0; tile < m_tilePage.size(); ++tile) {
        const int32_t page = m_tilePage[tile];
        if (page >= kFirstOwnPage && pageHasSource[static_cast<size_t>(page - kFirstOwnPage)])
            d[tile] = 0;
    }
    chebyshevTransform(d, m_tiles[0], m_tiles[1], m_tiles[2], kFar);
    m_tileSkip.resize(d.size());
    for (size_t t = 0; t < d.size(); ++t)
        m_tileSkip[t] = static_cast<uint8_t>(std::min<int>(255, d[t]));

    constexpr int kFarBlocks = kTileBlocks + 1;
    m_blockSkip.assign(m_flags.size(), 1);  // the constant pages: no source, no skip
    tbb::parallel_for(size_t(0), pages, [&](size_t p) {
        const int* t = m_ownTiles.data() + 3 * p;
        uint8_t* out = m_blockSkip.data() + (p + kFirstOwnPage) * kPageEntries;
        std::fill(out, out + kPageEntries, static_cast<uint8_t>(kFarBlocks));
        // The window: 3 x 3 x 3 tiles, bit x of row (y, z) = block x of the window.
        constexpr int W = kWindow;
        uint32_t win[W][W] = {};
        bool any = false;
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int n[3] = {t[0] + dx, t[1] + dy, t[2] + dz};
                    if (n[0] < 0 || n[1] < 0 || n[2] < 0 || n[0] >= m_tiles[0] ||
                        n[1] >= m_tiles[1] || n[2] >= m_tiles[2])
                        continue;
                    const int32_t page =
                        m_tilePage[(static_cast<size_t>(n[2]) * m_tiles[1] + n[1]) * m_tiles[0] +
                                   n[0]];
                    if (page < kFirstOwnPage) continue;
                    const uint8_t* r = rows.data() + static_cast<size_t>(page - kFirstOwnPage) * 64;
                    for (int z = 0; z < kTileBlocks; ++z)
                        for (int y = 0; y < kTileBlocks; ++y) {
                            const uint32_t bits = r[z * kTileBlocks + y];
                            any |= bits != 0;
                            win[(dz + 1) * kTileBlocks + z][(dy + 1) * kTileBlocks + y] |=
                                bits << ((dx + 1) * kTileBlocks);
                        }
                }
        if (any) centreTileDistances(win, out);
    });
}

// Sphere tracing needs the field's Lipschitz bound (Liktor 2008, §2.2); a grid's global bound is
// its steepest cell's. An open mesh signed by its winding number
// has a few very steep cells: across the surface that closes each hole (decision 0004), samples
// flip from +d to -d, d up to the band, so the Stanford bunny's bound is 6 sqrt 3 = 10.4 where its
// body's cells need 1.4. Divided by that everywhere, the field reads a tenth of the distance:
// sphere tracing crawls, and Keinert's screen-space test (§3.2) takes the band, and non-surface
// blocks next to a steep cell, for surfaces (decision 0012).
//
// So blocks get one of two bounds: the global one, or a second, lower one where every cell within
// one block (of the surface blocks near an own page's block; near the tile, for blocks of the
// shared constant pages) is at most that steep. The second is the one of the needs, at most half
// the global bound, that minimizes the bounds' sum over the blocks near surface.
// gridDistanceBound(p) = f(p) / L_b for p in block b is still at most the distance r to the
// reconstruction's zero set: when r < B h, the segment to the nearest zero stays within b and
// the blocks around it, where the slope is at most L_b; otherwise |f| <= background <= L_b B h <
// r, given L_b >= background / (B h) (and >= 1). Two bounds, not one per block: normals
// estimated across a face between blocks of different bounds see two scales, a seam; a bound per
// block put seams on every flat face of a baked cube. Grids whose steepest cell is less than
// twice their gentlest need (closed meshes) keep the global bound everywhere.
void Grid::computeLocalLipschitz(const std::vector<float>& blockWorst) {
    std::vector<float> tileWorst(m_tilePage.size(), 0.0f), slotWorst(m_flags.size(), 0.0f);
    const GridView table = view();
    // Each block's bound covers its 26 neighbours' cells too: slotWorst (and tileWorst) from it,
    // blocks in parallel (a maximum taken by compare-and-swap: the same in any order).
    auto raise = [](float& target, float w) {
        std::atomic_ref<float> ref(target);
        float seen = ref.load(std::memory_order_relaxed);
        while (w > seen && !ref.compare_exchange_weak(seen, w, std::memory_order_relaxed)) {
        }
    };
    auto dilate = [&] {
        forEachPagedBlock(
            [&](int bi, int bj, int bk, size_t slot) {
                const int32_t data = m_blockData[slot];
                if (data < 0) return;
                const float w = blockWorst[static_cast<size_t>(data)];
                const int b[3] = {bi, bj, bk};
                int lo[3], hi[3];
                for (int a = 0; a < 3; ++a) {
                    lo[a] = std::max(0, b[a] - 1);
                    hi[a] = std::min(m_blocks[a] - 1, b[a] + 1);
                }
                for (int k = lo[2]; k <= hi[2]; ++k)
                    for (int j = lo[1]; j <= hi[1]; ++j)
                        for (int i = lo[0]; i <= hi[0]; ++i) {
                            const size_t tile = table.tileIndex(i, j, k);
                            raise(tileWorst[tile], w);
                            const int32_t page = m_tilePage[tile];
                            if (page < kFirstOwnPage) continue;  // shared: the tile's bound
                            raise(slotWorst[static_cast<size_t>(page) * kPageEntries +
                                            pageLocal(i, j, k)],
                                  w);
                        }
            },
            true);
    };
    dilate();
    // The slope each bound must cover, never below the floor.
    const float floor =
        std::max(1.0f, m_background / (static_cast<float>(m_blockSize) * m_shape.voxelSize));
    auto need = [&](float worst) { return std::max(floor, std::sqrt(worst) / m_shape.voxelSize); };
    // The second bound: of the needs at most half the global bound, the one that minimizes the sum
    // of the bounds over the blocks near surface (each block's bound is what slows its rays).
    // Sorted in slotWorst's own buffer (millions of slots at 2048 cells: no second array), which
    // the dilation then fills again.
    std::vector<float>& needs = slotWorst;
    size_t nonzero = 0;
    for (float w : slotWorst)
        if (w > 0) needs[nonzero++] = need(w);
    needs.resize(nonzero);
    tbb::parallel_sort(needs.begin(), needs.end());
    m_gentleLipschitz = m_lipschitz;
    double best = static_cast<double>(needs.size()) * m_lipschitz;
    for (size_t i = 0; i < needs.size() && needs[i] <= 0.5f * m_lipschitz; ++i) {
        if (i + 1 < needs.size() && needs[i + 1] == needs[i]) continue;
        const double cost = static_cast<double>(i + 1) * needs[i] +
                            static_cast<double>(needs.size() - i - 1) * m_lipschitz;
        if (cost < best) {
            best = cost;
            m_gentleLipschitz = needs[i];
        }
    }
    slotWorst.assign(m_flags.size(), 0.0f);
    dilate();
    const float gentle = m_gentleLipschitz < m_lipschitz ? m_gentleLipschitz : -1.0f;
    // A NaN need (a damaged file) compares false: the global bound.
    auto code = [&](float worst) { return static_cast<uint8_t>(need(worst) <= gentle ? 1 : 0); };
    m_tileLipschitz.resize(tileWorst.size());
    for (size_t t = 0; t < tileWorst.size(); ++t) m_tileLipschitz[t] = code(tileWorst[t]);
    m_blockLipschitz.resize(slotWorst.size());
    tbb::parallel_for(size_t(0), slotWorst.size(),
                      [&](size_t s) { m_blockLipschitz[s] = code(slotWorst[s]); });
}

}  // namespace sdft
