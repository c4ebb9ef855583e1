#include "sdftrace/io/vdb_io.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <sstream>

#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/io/atomic_file.h"
#include "vdb_reader.h"

namespace sdft {

namespace {
void initOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}
}  // namespace

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
    for (const vdb::Leaf& leaf : t.leaves)
        for (int i = 0; i < 512; ++i)
            if ((leaf.active[i >> 6] >> (i & 63)) & 1u)
                include(leaf.origin[0] + (i >> 6), leaf.origin[1] + ((i >> 3) & 7),
                        leaf.origin[2] + (i & 7), 1);
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

}  // namespace

// The tree straight into a sparse block grid: blocks that touch a leaf (or whose corners are near
// or of both signs) get their samples from the tree; every other block lies in one tile region
// and takes its flag from the sign there. Same grid as sampling the dense active region and
// sparsifying it (Grid::sparseFromDense), without the dense array.
Grid loadVdb(const std::string& path, const VdbImportOptions& options) {
    const vdb::FloatGrid g = vdb::readVdbFile(path);
    const vdb::Tree& t = g.tree;
    std::array<int32_t, 3> lo{}, hi{};
    if (!activeBounds(t, lo, hi))
        throw InputError(path + ": grid '" + g.name + "' has no active voxels");
    GridShape shape;
    const float h = static_cast<float>(g.voxelSize);
    for (int a = 0; a < 3; ++a) {
        const int64_t dim = static_cast<int64_t>(hi[a]) - lo[a] + 1;
        if (dim < 2 || dim > 32768)
            throw InputError(path + ": active region of " + std::to_string(dim) +
                             " voxels along an axis (accepted: 2 to 32768)");
        shape.cells[a] = static_cast<int>(dim - 1);
        shape.origin[a] = static_cast<float>(g.translation[a] + lo[a] * g.voxelSize);
        if (!(std::fabs(shape.origin[a]) <= kMaxCoordinate))
            throw InputError(path + ": the grid lies beyond +-1e9");
    }
    shape.voxelSize = h;
    for (const vdb::Leaf& leaf : t.leaves)
        for (float v : leaf.values)
            if (!std::isfinite(v))
                throw InputError(path + ": non-finite values in grid '" + g.name + "'");
    const int B = options.blockSize, V = B + 1;
    const float bandVoxels = std::max(options.minBandVoxels, std::fabs(t.background) / h * 0.999f);
    const float band = bandVoxels * h;
    int blocks[3];
    for (int a = 0; a < 3; ++a) blocks[a] = (shape.cells[a] + B - 1) / B;
    const size_t numBlocks = static_cast<size_t>(blocks[0]) * blocks[1] * blocks[2];
    checkMemoryBudget(static_cast<double>(numBlocks) * 5 +
                          static_cast<double>(t.leaves.size()) * 8 * V * V * V * sizeof(float),
                      path, "the sparse grid's block tables and surface blocks",
                      "resample the level set coarser");
    // The active region in 8^3-voxel regions on the VDB leaf grid: per region its leaf (or -1)
    // and otherwise its tile value, so that a sample is two array reads, not a tree descent.
    int32_t r0[3], rn[3];
    for (int a = 0; a < 3; ++a) {
        r0[a] = lo[a] >> 3;
        rn[a] = (hi[a] >> 3) - r0[a] + 1;
    }
    const size_t numRegions = static_cast<size_t>(rn[0]) * rn[1] * rn[2];
    checkMemoryBudget(
        static_cast<double>(numRegions) * 8, path,
        "an index of the active region's " + std::to_string(numRegions) + " leaf-sized regions",
        "resample the level set coarser");
    std::vector<int32_t> regionLeaf(numRegions, -1);
    std::vector<float> regionValue(numRegions);
    auto regionOf = [&](int32_t x, int32_t y, int32_t z) {
        return (static_cast<size_t>((z >> 3) - r0[2]) * rn[1] + ((y >> 3) - r0[1])) * rn[0] +
               ((x >> 3) - r0[0]);
    };
    tbb::parallel_for(0, rn[2], [&](int rz) {
        for (int ry = 0; ry < rn[1]; ++ry)
            for (int rx = 0; rx < rn[0]; ++rx) {
                const int32_t x = (r0[0] + rx) * 8, y = (r0[1] + ry) * 8, z = (r0[2] + rz) * 8;
                regionValue[regionOf(x, y, z)] = t.value(x, y, z);
            }
    });
    for (size_t i = 0; i < t.leaves.size(); ++i) {
        const auto& o = t.leaves[i].origin;
        bool inside = true;
        for (int a = 0; a < 3; ++a)
            inside = inside && o[a] >= r0[a] * 8 && o[a] < (r0[a] + rn[a]) * 8;
        if (inside) regionLeaf[regionOf(o[0], o[1], o[2])] = static_cast<int32_t>(i);
    }
    // Vertex (i, j, k), clamped to the grid as GridView::vertex clamps, is voxel lo + (i, j, k).
    auto voxel = [&](int i, int j, int k, int a) {
        const int v[3] = {i, j, k};
        return lo[a] + std::min(v[a], shape.cells[a]);
    };
    auto value = [&](int i, int j, int k) {
        const int32_t x = voxel(i, j, k, 0), y = voxel(i, j, k, 1), z = voxel(i, j, k, 2);
        const size_t r = regionOf(x, y, z);
        const int32_t leaf = regionLeaf[r];
        return leaf < 0 ? regionValue[r]
                        : t.leaves[leaf].values[((x & 7) << 6) | ((y & 7) << 3) | (z & 7)];
    };
    std::vector<uint8_t> flags(numBlocks);
    // Pass 1, cheap: which blocks need their samples (they touch a leaf, or their tile corners
    // are near the surface or of both signs), the others flagged by their tile's sign. Tiles near
    // zero or a band wider than the level set's can make far more candidates than the leaves
    // suggest: their samples are checked against the budget before any is computed.
    constexpr uint8_t kCandidate = 3;
    std::atomic<size_t> candidates{0};
    tbb::parallel_for(0, blocks[2], [&](int bk) {
        size_t count = 0;
        for (int bj = 0; bj < blocks[1]; ++bj)
            for (int bi = 0; bi < blocks[0]; ++bi) {
                const int b[3] = {bi, bj, bk};
                bool touches = false, anyNeg = false, anyPos = false, near = false;
                for (int corner = 0; corner < 8; ++corner) {
                    int vtx[3];
                    for (int a = 0; a < 3; ++a) vtx[a] = b[a] * B + ((corner >> a) & 1) * B;
                    int32_t c[3];
                    for (int a = 0; a < 3; ++a) c[a] = lo[a] + std::min(vtx[a], shape.cells[a]);
                    touches |= regionLeaf[regionOf(c[0], c[1], c[2])] >= 0;
                    const float v = value(vtx[0], vtx[1], vtx[2]);
                    anyNeg |= v < 0;
                    anyPos |= v >= 0;
                    near |= std::fabs(v) < band;
                }
                const size_t block = (static_cast<size_t>(bk) * blocks[1] + bj) * blocks[0] + bi;
                if (touches || near || (anyNeg && anyPos)) {
                    flags[block] = kCandidate;
                    ++count;
                } else {
                    flags[block] =
                        static_cast<uint8_t>(anyNeg ? BlockFlag::Inside : BlockFlag::Outside);
                }
            }
        candidates += count;
    });
    checkMemoryBudget(
        numBlocks * 5.0 + 2.0 * V * V * V * sizeof(float) * candidates.load(), path,
        "the samples of " + std::to_string(candidates.load()) + " blocks near its surface",
        "resample the level set coarser");
    // Pass 2: the candidates' samples; a candidate whose samples are all far is not a surface
    // block after all.
    std::vector<std::vector<float>> slabSamples(blocks[2]);
    tbb::parallel_for(0, blocks[2], [&](int bk) {
        std::vector<float> local(static_cast<size_t>(V) * V * V);
        for (int bj = 0; bj < blocks[1]; ++bj)
            for (int bi = 0; bi < blocks[0]; ++bi) {
                const size_t block = (static_cast<size_t>(bk) * blocks[1] + bj) * blocks[0] + bi;
                if (flags[block] != kCandidate) continue;
                bool anyNeg = false, anyPos = false, near = false;
                for (int k = 0; k < V; ++k)
                    for (int j = 0; j < V; ++j)
                        for (int i = 0; i < V; ++i) {
                            float v = value(bi * B + i, bj * B + j, bk * B + k);
                            v = v < 0 ? -std::fmin(-v, band) : std::fmin(v, band);
                            local[(static_cast<size_t>(k) * V + j) * V + i] = v;
                            anyNeg |= v < 0;
                            anyPos |= v >= 0;
                            near |= std::fabs(v) < band;
                        }
                if (near || (anyNeg && anyPos)) {
                    flags[block] = static_cast<uint8_t>(BlockFlag::Surface);
                    slabSamples[bk].insert(slabSamples[bk].end(), local.begin(), local.end());
                } else {
                    flags[block] =
                        static_cast<uint8_t>(anyNeg ? BlockFlag::Inside : BlockFlag::Outside);
                }
            }
    });
    std::vector<float> samples;
    size_t total = 0;
    for (const auto& s : slabSamples) total += s.size();
    samples.reserve(total);
    for (auto& s : slabSamples) {
        samples.insert(samples.end(), s.begin(), s.end());
        std::vector<float>().swap(s);
    }
    return Grid::sparseFromBuffers(shape, B, (bandVoxels - 1) * h, std::move(flags),
                                   std::move(samples), path);
}

void saveVdb(const Grid& grid, const std::string& path) {
    initOpenVdb();
    const GridShape& s = grid.shape();
    GridView v = grid.view();
    // Level sets keep a narrow band of about 3 voxels; ours is the sparse grid's band (its
    // background plus one voxel) or 3 voxels for dense grids.
    float band =
        grid.kind() == GridKind::Sparse ? grid.background() + s.voxelSize : 3.0f * s.voxelSize;
    auto out = openvdb::FloatGrid::create(band);
    out->setName("surface");
    out->setGridClass(openvdb::GRID_LEVEL_SET);
    auto xf = openvdb::math::Transform::createLinearTransform(s.voxelSize);
    xf->postTranslate(openvdb::Vec3d(s.origin.x, s.origin.y, s.origin.z));
    out->setTransform(xf);
    auto acc = out->getAccessor();
    // Only real samples become active: a sparse grid's surface blocks (its other blocks hold no
    // samples), a dense grid's samples within the band. Values are clamped to +-band as level sets
    // expect.
    auto put = [&](int i, int j, int k) {
        float value = v.vertex(i, j, k);
        if (grid.kind() == GridKind::Dense && std::fabs(value) >= band) return;
        acc.setValue(openvdb::Coord(i, j, k), std::clamp(value, -band, band));
    };
    if (grid.kind() == GridKind::Dense) {
        for (int k = 0; k <= s.cells[2]; ++k)
            for (int j = 0; j <= s.cells[1]; ++j)
                for (int i = 0; i <= s.cells[0]; ++i) put(i, j, k);
    } else {
        const int B = v.blockSize;
        for (int bk = 0; bk < v.blocks[2]; ++bk)
            for (int bj = 0; bj < v.blocks[1]; ++bj)
                for (int bi = 0; bi < v.blocks[0]; ++bi) {
                    size_t block = (static_cast<size_t>(bk) * v.blocks[1] + bj) * v.blocks[0] + bi;
                    if (v.blockData[block] < 0) continue;
                    for (int k = bk * B; k <= std::min((bk + 1) * B, s.cells[2]); ++k)
                        for (int j = bj * B; j <= std::min((bj + 1) * B, s.cells[1]); ++j)
                            for (int i = bi * B; i <= std::min((bi + 1) * B, s.cells[0]); ++i)
                                put(i, j, k);
                }
    }
    openvdb::tools::signedFloodFill(out->tree());
    // Encoded in memory, then written with every write checked.
    std::ostringstream bytes(std::ios::binary);
    try {
        openvdb::GridPtrVec grids{out};
        openvdb::io::Stream(bytes).write(grids);
    } catch (const std::exception& e) {
        throw InputError(path + ": cannot write OpenVDB file (" + e.what() + ")");
    }
    const std::string data = bytes.str();
    writeFileAtomically(path, data.data(), data.size());
}

}  // namespace sdft
