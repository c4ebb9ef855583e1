// Complete block grids (grid.h: Grid::completeFromDense, refreshComplete): every block keeps its
// samples. RTSDF regenerates a mesh's fine SDF every frame into one grid shape (Tan et al. 2022,
// §2.5.1); its 3D textures cover their volume, and so do these grids. Their layout is the shape's
// alone, so each frame refreshes the last frame's blocks in place of classifying, gathering and
// comparing them afresh (sparseFromDense), and the GPU refreshes them on the device with the same
// per-block function (complete_block.h).
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "sdftrace/core/error.h"
#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/field/complete_block.h"
#include "sdftrace/field/grid.h"
#include "sdftrace/field/sparse_grid_builder.h"

namespace sdft {

namespace {

// The refresh's view of `g`'s arrays for `samples`.
CompleteRefreshView refreshView(const Grid& g, const GridView& v, const std::vector<float>& samples,
                                float* blockSamples, uint64_t* cellMasks, float* worst) {
    CompleteRefreshView r;
    r.shape = g.shape();
    for (int a = 0; a < 3; ++a) r.blocks[a] = v.blocks[a];
    r.band = g.completeBand();
    r.dense = samples.data();
    r.blockNeighbors = v.blockNeighbors;
    r.surfaceBlocks = static_cast<int32_t>(g.surfaceBlockCount());
    r.blockSamples = blockSamples;
    r.cellMasks = cellMasks;
    r.worst = worst;
    return r;
}

void refreshAll(const CompleteRefreshView& r, int B) {
    tbb::parallel_for(tbb::blocked_range<int32_t>(0, r.surfaceBlocks, 64),
                      [&](const tbb::blocked_range<int32_t>& range) {
                          for (int32_t d = range.begin(); d != range.end(); ++d) {
                              if (B == 8)
                                  refreshCompleteBlock<8>(r, d);
                              else
                                  refreshCompleteBlock<4>(r, d);
                          }
                      });
}

}  // namespace

Grid Grid::completeFromDense(const GridShape& shape, const std::vector<float>& samples, int B,
                             float bandVoxels) {
    SDFT_CHECK(samples.size() == shape.vertexCount());
    SDFT_CHECK(B == 4 || B == 8);
    SDFT_CHECK(bandVoxels >= 2);
    int blocks[3];
    for (int a = 0; a < 3; ++a) blocks[a] = (shape.cells[a] + B - 1) / B;
    const size_t numBlocks = static_cast<size_t>(blocks[0]) * blocks[1] * blocks[2];
    if (numBlocks > static_cast<size_t>(INT32_MAX))
        throw InputError("complete grid: " + std::to_string(numBlocks) +
                         " blocks (at most 2^31 - 1 are accepted)");
    // Every block a surface block: numbered in flat block order, as refreshCompleteBlock assumes.
    const std::vector<uint8_t> flags(numBlocks, static_cast<uint8_t>(BlockFlag::Surface));
    const float band = bandVoxels * shape.voxelSize;
    SparseGridBuilder builder(shape, B, (bandVoxels - 1) * shape.voxelSize,
                              BlockTable::fromDense(blocks, flags, "dense samples"),
                              "dense samples");
    const int V = B + 1;
    const size_t vx = static_cast<size_t>(shape.cells[0]) + 1,
                 vy = static_cast<size_t>(shape.cells[1]) + 1;
    builder.forEachSurfaceBlock([&](int bi, int bj, int bk, int32_t data) {
        SDFT_CHECK(static_cast<size_t>(data) ==
                   (static_cast<size_t>(bk) * blocks[1] + bj) * blocks[0] + bi);
        float e[9 * 9 * 9];
        for (int z = 0; z < V; ++z)
            for (int y = 0; y < V; ++y)
                for (int x = 0; x < V; ++x) {
                    const size_t at =
                        (static_cast<size_t>(std::min(bk * B + z, shape.cells[2])) * vy +
                         static_cast<size_t>(std::min(bj * B + y, shape.cells[1]))) *
                            vx +
                        static_cast<size_t>(std::min(bi * B + x, shape.cells[0]));
                    const float s = samples[at];
                    e[(z * V + y) * V + x] = clampToBand(s, band);
                }
        // The entries past the grid's far faces private, whatever their values: no shared
        // constant block whose sharing a later frame's samples could undo.
        uint8_t past = 0;
        const int b[3] = {bi, bj, bk};
        for (int code = 1; code < 8; ++code)
            for (int a = 0; a < 3; ++a)
                if ((code >> a & 1) && b[a] + 1 >= blocks[a])
                    past |= static_cast<uint8_t>(1 << code);
        builder.addBlock(bi, bj, bk, e, past);
    });
    Grid g = builder.finish();
    g.m_complete = true;
    g.m_completeBand = band;
    return g;
}

Grid Grid::refreshComplete(const std::vector<float>& samples) const {
    SDFT_CHECK(m_complete);
    SDFT_CHECK(samples.size() == m_shape.vertexCount());
    Grid g;
    g.m_kind = m_kind;
    g.m_shape = m_shape;
    g.m_blockSize = m_blockSize;
    for (int a = 0; a < 3; ++a) {
        g.m_blocks[a] = m_blocks[a];
        g.m_tiles[a] = m_tiles[a];
    }
    g.m_background = m_background;
    g.m_tilePage = m_tilePage;
    g.m_ownTiles = m_ownTiles;
    g.m_flags = m_flags;
    g.m_blockData = m_blockData;
    g.m_blockNeighbors = m_blockNeighbors;
    g.m_surfaceBlocks = m_surfaceBlocks;
    g.m_apronFrom = m_apronFrom;
    g.m_apronCode = m_apronCode;
    g.m_complete = true;
    g.m_completeBand = m_completeBand;
    // Zeros where no vertex is written (a private apron block's entries of other codes), as the
    // builder leaves them.
    assignHuge(g.m_blockSamples, m_blockSamples.size(), 0.0f);
    assignHuge(g.m_cellMasks, m_cellMasks.size(), uint64_t{0});
    std::vector<float> worst(m_surfaceBlocks, 0.0f);
    refreshAll(refreshView(g, g.view(), samples, g.m_blockSamples.data(), g.m_cellMasks.data(),
                           worst.data()),
               m_blockSize);
    g.finishComplete(worst);
    return g;
}

void Grid::finishComplete(const std::vector<float>& blockWorst) {
    float worst = 0;
    for (float w : blockWorst) worst = std::max(worst, w);
    // SparseGridBuilder::finish's bound, skip tables and local bounds.
    m_lipschitz = std::max(1.0f, std::sqrt(worst) / m_shape.voxelSize);
    computeBlockSkip();
    computeLocalLipschitz(blockWorst);
}

}  // namespace sdft
