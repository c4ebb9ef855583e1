// Grids sampled from analytic fields: reconstruction error, sparse == dense in the band, block
// flags, cell masks, the Lipschitz bound, and grids inside tapes.
#include "sdftrace/field/grid.h"

#include <gtest/gtest.h>

#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/field/test_util.h"

namespace sdft {
namespace {

struct Sampled {
    NodePtr node;
    Tape tape;
    Grid dense, sparse;
};

Sampled sampleTorusAndBox(int resolution, int blockSize) {
    NodePtr n = node::unite(
        {node::torus(0.8f, 0.25f), node::translate(node::box({0.5f, 0.6f, 0.5f}), {0, 0.2f, 0})});
    Tape tape = compileTape(n, {.boundsCulling = false});
    Bounds3 region = nodeBounds(*n);
    GridShape shape = gridShapeFor(region, SampleOptions{.resolution = resolution,
                                                         .kind = GridKind::Sparse,
                                                         .blockSize = blockSize,
                                                         .bandVoxels = 3});
    std::vector<float> samples = sampleVertices(tape, shape);
    return {n, std::move(tape), Grid::dense(shape, samples),
            Grid::sparseFromDense(shape, samples, blockSize, 3)};
}

TEST(Grid, TrilinearReconstructionIsWithinAVoxelOfTheExactField) {
    Sampled s = sampleTorusAndBox(64, 4);
    GridView v = s.dense.view();
    float h = s.dense.shape().voxelSize;
    testing::Rng rng(1);
    Bounds3 b = s.dense.shape().bounds();
    for (int i = 0; i < 20000; ++i) {
        Vec3 p = rng.inBox(b.lo, b.hi);
        // Interpolating exact distances errs by at most half a cell diagonal (sqrt(3)/2 h).
        ASSERT_NEAR(v.sample(p), s.tape.eval(p), 0.87f * h);
    }
}

TEST(Grid, SparseMatchesDenseInsideTheBandAndKeepsTheSignElsewhere) {
    for (int B : {4, 8}) {
        Sampled s = sampleTorusAndBox(64, B);
        GridView d = s.dense.view(), sp = s.sparse.view();
        float h = s.dense.shape().voxelSize;
        testing::Rng rng(2);
        Bounds3 b = s.dense.shape().bounds();
        for (int i = 0; i < 20000; ++i) {
            Vec3 p = rng.inBox(b.lo, b.hi);
            float dv = d.sample(p), sv = sp.sample(p);
            // Equal where every corner of p's cell is in the band (beyond it samples are clamped).
            Vec3 g = (p - s.dense.shape().origin) / h;
            float c[8];
            d.cellCorners(std::min(int(g.x), s.dense.shape().cells[0] - 1),
                          std::min(int(g.y), s.dense.shape().cells[1] - 1),
                          std::min(int(g.z), s.dense.shape().cells[2] - 1), c);
            bool inBand = true;
            for (float corner : c) inBand &= std::fabs(corner) < 3 * h;
            if (inBand) {
                ASSERT_EQ(dv, sv) << "B=" << B;
            }
            ASSERT_EQ(dv < 0, sv < 0) << "B=" << B;
            // Outside the band the sparse value is a smaller-magnitude bound.
            ASSERT_LE(std::fabs(sv), std::fabs(dv) + 1e-6f);
        }
        size_t in, out, surf;
        s.sparse.blockCounts(in, out, surf);
        EXPECT_GT(in, 0u);
        EXPECT_GT(out, 0u);
        EXPECT_GT(surf, 0u);
        EXPECT_LT(s.sparse.memoryBytes(), s.dense.memoryBytes());
    }
}

// Decision 10: a surface block stores its B^3 own samples and reads its apron through the
// neighbour table; every cell must read exactly the (B+1)^3 vertices the block was built with,
// also where an apron disagrees with its owner (a private block) and at grid faces that cut a
// block (61 cells) or end on one (64 cells).
TEST(Grid, CompactBlocksGiveEveryCellTheCornersItWasBuiltWith) {
    for (int B : {4, 8})
        for (int res : {61, 64}) {
            const Sampled s = sampleTorusAndBox(res, B);
            const Grid& g = s.sparse;
            const int V = B + 1;
            const size_t per = static_cast<size_t>(V) * V * V, own = static_cast<size_t>(B) * B * B;
            // Consistent aprons: the owner's samples or one clamped value; a few constant blocks.
            EXPECT_LE(g.blockSamples().size(), (g.surfaceBlockCount() + 4) * own)
                << B << " " << res;
            std::vector<float> built = g.expandedBlockSamples();
            ASSERT_EQ(built.size(), g.surfaceBlockCount() * per);
            // Every 7th block's far corner and one vertex of its +x face made to disagree with
            // their owners (private apron blocks, or constants of another value).
            for (size_t b = 0; b < g.surfaceBlockCount(); b += 7) {
                built[b * per + per - 1] += 1e-3f;
                built[b * per + static_cast<size_t>(B)] += 1e-3f;
            }
            const Grid changed = Grid::sparseFromBuffers(g.shape(), B, g.background(),
                                                         g.denseFlags(), built, "test");
            EXPECT_EQ(changed.expandedBlockSamples(), built) << B << " " << res;
            EXPECT_GT(changed.blockSamples().size(), g.blockSamples().size());
            // Each cell of each surface block, read through the view, against the built vertices.
            const GridView v = changed.view();
            size_t cells = 0;
            changed.forEachPagedBlock(
                [&](int bi, int bj, int bk, size_t slot) {
                    const int32_t data = v.blockData[slot];
                    if (data < 0) return;
                    const float* e = built.data() + static_cast<size_t>(data) * per;
                    for (int z = 0; z < B; ++z)
                        for (int y = 0; y < B; ++y)
                            for (int x = 0; x < B; ++x) {
                                const int i = bi * B + x, j = bj * B + y, k = bk * B + z;
                                if (i >= g.shape().cells[0] || j >= g.shape().cells[1] ||
                                    k >= g.shape().cells[2])
                                    continue;
                                float c[8], d[8];
                                v.cellCorners(i, j, k, c);
                                v.blockCellCorners(data, x, y, z, d);
                                for (int n = 0; n < 8; ++n) {
                                    const float want =
                                        e[((z + (n >> 2)) * V + y + ((n >> 1) & 1)) * V + x +
                                          (n & 1)];
                                    ASSERT_EQ(c[n], want) << i << " " << j << " " << k << " " << n;
                                    ASSERT_EQ(d[n], want) << i << " " << j << " " << k << " " << n;
                                }
                                ++cells;
                            }
                },
                false);
            EXPECT_GT(cells, 1000u);
        }
}

// The last vertex of an axis whose cell count is a multiple of B lies past the grid's last block:
// the blocks at that face read it through their neighbour entries (decision 10). Every vertex
// and every stencil there must still read the samples the grid was built from.
TEST(Grid, FarFaceVerticesComeThroughTheNeighbourEntries) {
    for (int B : {4, 8}) {
        GridShape shape;
        shape.cells[0] = 2 * B, shape.cells[1] = 3 * B, shape.cells[2] = B + 3;  // z cuts a block
        shape.voxelSize = 0.1f;
        std::vector<float> samples(shape.vertexCount());
        size_t n = 0;
        for (int k = 0; k <= shape.cells[2]; ++k)
            for (int j = 0; j <= shape.cells[1]; ++j)
                for (int i = 0; i <= shape.cells[0]; ++i)
                    samples[n++] = 0.1f * (i - 0.3f * j + 0.2f * k - 2.5f);  // varies on every face
        const Grid g = Grid::sparseFromDense(shape, samples, B, 100);
        const GridView v = g.view();
        n = 0;
        for (int k = 0; k <= shape.cells[2]; ++k)
            for (int j = 0; j <= shape.cells[1]; ++j)
                for (int i = 0; i <= shape.cells[0]; ++i)
                    ASSERT_EQ(v.vertex(i, j, k), samples[n++])
                        << B << ": " << i << "," << j << "," << k;
        for (int k = 0; k < shape.cells[2]; ++k)
            for (int j = 0; j < shape.cells[1]; ++j)
                for (int i = 0; i < shape.cells[0]; ++i) {
                    float nb[4][4][4];
                    v.gradientStencil(i, j, k, nb);
                    for (int z = 0; z < 4; ++z)
                        for (int y = 0; y < 4; ++y)
                            for (int x = 0; x < 4; ++x) {
                                if ((x == 0 || x == 3) + (y == 0 || y == 3) + (z == 0 || z == 3) >
                                    1)
                                    continue;
                                ASSERT_EQ(nb[z][y][x], v.vertex(i + x - 1, j + y - 1, k + z - 1))
                                    << B << ": cell " << i << "," << j << "," << k;
                            }
                }
        // The far faces' vertices are not one value: private apron blocks hold them.
        EXPECT_GT(g.blockSamples().size(), g.surfaceBlockCount() * B * B * B);
    }
}

TEST(Grid, CellMasksMarkExactlyTheCellsWithASignChange) {
    for (int blockSize : {4, 8}) {
        // 45 cells: the last blocks are cut by the grid's faces.
        Sampled s = sampleTorusAndBox(45, blockSize);
        GridView v = s.sparse.view();
        const int B = v.blockSize;
        int marked = 0;
        for (int k = 0; k < v.shape.cells[2]; ++k)
            for (int j = 0; j < v.shape.cells[1]; ++j)
                for (int i = 0; i < v.shape.cells[0]; ++i) {
                    float c[8];
                    v.cellCorners(i, j, k, c);
                    bool neg = false, pos = false;
                    for (float x : c) (x < 0 ? neg : pos) = true;
                    int32_t data = v.blockData[v.blockSlot(i / B, j / B, k / B)];
                    bool bit = false;
                    if (data >= 0) {
                        int local = ((k % B) * B + j % B) * B + i % B;
                        bit = (v.cellMasks[static_cast<size_t>(data) * v.wordsPerMask() +
                                           local / 64] >>
                               (local % 64)) &
                              1;
                    }
                    ASSERT_EQ(bit, neg && pos) << i << "," << j << "," << k << " B=" << B;
                    marked += bit;
                }
        EXPECT_GT(marked, 100);
    }
}

// A sparse grid's Lipschitz bound is the largest per-cell bound over its surface blocks' cells
// (each axis: the largest |edge difference| / h), never below 1.
TEST(Grid, SparseLipschitzBoundIsTheLargestCellBound) {
    for (int blockSize : {4, 8}) {
        Sampled s = sampleTorusAndBox(45, blockSize);
        const GridView v = s.sparse.view();
        const int B = v.blockSize;
        float worst = 0;
        for (int k = 0; k < v.shape.cells[2]; ++k)
            for (int j = 0; j < v.shape.cells[1]; ++j)
                for (int i = 0; i < v.shape.cells[0]; ++i) {
                    if (v.blockData[v.blockSlot(i / B, j / B, k / B)] < 0) continue;
                    float c[8];
                    v.cellCorners(i, j, k, c);
                    float g[3] = {0, 0, 0};
                    for (int n = 0; n < 8; ++n)
                        for (int a = 0; a < 3; ++a)
                            if (!(n & (1 << a)))
                                g[a] = std::max(g[a], std::fabs(c[n | (1 << a)] - c[n]));
                    worst = std::max(worst, g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
                }
        EXPECT_FLOAT_EQ(s.sparse.lipschitz(), std::max(1.0f, std::sqrt(worst) / v.shape.voxelSize))
            << "B=" << B;
        EXPECT_GT(s.sparse.lipschitz(), 1.0f);  // a box corner's clamped band is steeper than 1
    }
}

// The normal estimator's stencil reads what vertex() reads, clamping included, for dense and
// sparse grids (both block sizes), at cells inside, at block seams and on the grid's faces.
TEST(Grid, GradientStencilMatchesVertexLookups) {
    for (int B : {4, 8}) {
        Sampled s = sampleTorusAndBox(37, B);
        for (const Grid* grid : {&s.dense, &s.sparse}) {
            const GridView v = grid->view();
            int compared = 0;
            for (int k = 0; k < v.shape.cells[2]; k += 3)
                for (int j = 0; j < v.shape.cells[1]; j += 2)
                    for (int i = 0; i < v.shape.cells[0]; ++i) {
                        float nb[4][4][4];
                        v.gradientStencil(i, j, k, nb);
                        for (int z = 0; z < 4; ++z)
                            for (int y = 0; y < 4; ++y)
                                for (int x = 0; x < 4; ++x) {
                                    const int outer = (x == 0 || x == 3) + (y == 0 || y == 3) +
                                                      (z == 0 || z == 3);
                                    if (outer > 1) continue;
                                    ASSERT_EQ(nb[z][y][x],
                                              v.vertex(i + x - 1, j + y - 1, k + z - 1))
                                        << "B=" << B << " cell " << i << "," << j << "," << k;
                                    ++compared;
                                }
                    }
            EXPECT_GT(compared, 100000);
        }
    }
}

TEST(Grid, LipschitzBoundHoldsForTheReconstruction) {
    Sampled s = sampleTorusAndBox(40, 4);
    GridView v = s.dense.view();
    Bounds3 b = s.dense.shape().bounds().expanded(0.5f);
    testing::Rng rng(3);
    float worst = 0;
    for (int i = 0; i < 50000; ++i) {
        Vec3 a = rng.inBox(b.lo, b.hi);
        Vec3 c = a + rng.direction() * rng.uniform(1e-3f, 0.05f);
        worst = std::max(worst, std::fabs(v.sample(a) - v.sample(c)) / length(a - c));
    }
    EXPECT_LE(worst, s.dense.lipschitz() * 1.001f);
    EXPECT_GE(s.dense.lipschitz(), 1.0f);
    EXPECT_LE(s.dense.lipschitz(), 1.7321f);  // exact distances: each axis difference <= h
}

TEST(Grid, GridNodesEvaluateInTapesLikeTheTreeAndMixWithAnalyticObjects) {
    Sampled s = sampleTorusAndBox(32, 4);
    auto grid = std::make_shared<Grid>(std::move(s.sparse));
    NodePtr mixed = node::unite({node::translate(node::grid(grid), {1, 0, 0}), node::sphere(0.3f)});
    Tape tape = compileTape(mixed);
    testing::Rng rng(4);
    std::vector<float> x(500), y(500), z(500), out(500);
    for (int i = 0; i < 500; ++i) {
        Vec3 p = rng.inCube(2.5f);
        x[i] = p.x, y[i] = p.y, z[i] = p.z;
        ASSERT_NEAR(tape.eval(p), evalTree(*mixed, p), 1e-5f);
    }
    BatchScratch scratch;
    tape.evalBatch(x.data(), y.data(), z.data(), out.data(), 500, scratch);
    for (int i = 0; i < 500; ++i) ASSERT_EQ(out[i], tape.eval({x[i], y[i], z[i]}));
}

}  // namespace
}  // namespace sdft
