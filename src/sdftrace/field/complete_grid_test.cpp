// Complete block grids (Grid::completeFromDense, refreshComplete): the reconstruction, bounds and
// skip tables of sparseFromDense's grid where every block lies in the band, and a refresh equal,
// array for array, to a complete grid built afresh from the same samples.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "sdftrace/field/complete_skip.h"
#include "sdftrace/field/grid.h"
#include "sdftrace/field/grid_distance.h"
#include "sdftrace/field/test_grid_fields.h"
#include "sdftrace/field/test_util.h"

namespace sdft {
namespace {

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Every view value a tracer reads, of two grids that must reconstruct alike: each vertex and
// cell corner, the bounds and skip distances of every block (by its coordinates) and tile, and
// the distance bound at random points in and around the box.
void expectSameField(const Grid& a, const Grid& b) {
    const GridView u = a.view(), v = b.view();
    ASSERT_EQ(u.lipschitz, v.lipschitz);
    ASSERT_EQ(u.lipschitzLevel[1], v.lipschitzLevel[1]);
    const GridShape& s = a.shape();
    for (int k = 0; k <= s.cells[2]; ++k)
        for (int j = 0; j <= s.cells[1]; ++j)
            for (int i = 0; i <= s.cells[0]; ++i)
                ASSERT_TRUE(sameBits(u.vertex(i, j, k), v.vertex(i, j, k)))
                    << "vertex " << i << " " << j << " " << k;
    for (int k = 0; k < s.cells[2]; ++k)
        for (int j = 0; j < s.cells[1]; ++j)
            for (int i = 0; i < s.cells[0]; ++i) {
                float c[8], d[8];
                u.cellCorners(i, j, k, c);
                v.cellCorners(i, j, k, d);
                for (int n = 0; n < 8; ++n)
                    ASSERT_TRUE(sameBits(c[n], d[n])) << "cell " << i << " " << j << " " << k;
            }
    for (int bk = 0; bk < u.blocks[2]; ++bk)
        for (int bj = 0; bj < u.blocks[1]; ++bj)
            for (int bi = 0; bi < u.blocks[0]; ++bi) {
                const size_t x = u.blockSlot(bi, bj, bk), y = v.blockSlot(bi, bj, bk);
                ASSERT_EQ(u.blockSkip[x], v.blockSkip[y]) << bi << " " << bj << " " << bk;
                ASSERT_EQ(u.blockLipschitz[x], v.blockLipschitz[y]);
                const int32_t da = u.blockData[x], db = v.blockData[y];
                ASSERT_EQ(da >= 0, db >= 0);
                if (da < 0) continue;
                for (int w = 0; w < u.wordsPerMask(); ++w)
                    ASSERT_EQ(u.cellMasks[static_cast<size_t>(da) * u.wordsPerMask() + w],
                              v.cellMasks[static_cast<size_t>(db) * v.wordsPerMask() + w]);
            }
    ASSERT_EQ(a.tileSkip(), b.tileSkip());
    ASSERT_EQ(a.tileLipschitz(), b.tileLipschitz());
    testing::Rng rng(3);
    const Bounds3 box = s.bounds();
    for (int n = 0; n < 4000; ++n) {
        const Vec3 p = rng.inBox(box.lo - Vec3(0.2f), box.hi + Vec3(0.2f));
        ASSERT_TRUE(sameBits(gridDistanceBound(u, p), gridDistanceBound(v, p)));
    }
}

// Two grids array for array: the same layout and the same values.
void expectSameArrays(const Grid& a, const Grid& b) {
    EXPECT_EQ(a.lipschitz(), b.lipschitz());
    EXPECT_EQ(a.background(), b.background());
    EXPECT_EQ(a.tilePage(), b.tilePage());
    EXPECT_EQ(a.flags(), b.flags());
    EXPECT_EQ(a.blockData(), b.blockData());
    EXPECT_EQ(a.blockNeighbors(), b.blockNeighbors());
    ASSERT_EQ(a.blockSamples().size(), b.blockSamples().size());
    EXPECT_EQ(0, std::memcmp(a.blockSamples().data(), b.blockSamples().data(),
                             a.blockSamples().size() * sizeof(float)));
    EXPECT_EQ(a.cellMasks(), b.cellMasks());
    EXPECT_EQ(a.blockSkip(), b.blockSkip());
    EXPECT_EQ(a.tileSkip(), b.tileSkip());
    EXPECT_EQ(a.blockLipschitz(), b.blockLipschitz());
    EXPECT_EQ(a.tileLipschitz(), b.tileLipschitz());
    EXPECT_EQ(a.view().lipschitzLevel[1], b.view().lipschitzLevel[1]);
}

struct Case {
    int n[3];
    int B;
    float band;  // voxels
};

// Shapes whose cell counts are and are not multiples of the block size, and tiles cut by the
// grid's faces.
constexpr Case kCases[] = {{{40, 40, 40}, 4, 1e6f},
                           {{37, 29, 45}, 4, 1e6f},
                           {{70, 33, 48}, 8, 1e6f},
                           {{21, 66, 35}, 8, 500.0f},
                           {{44, 36, 52}, 4, 80.0f}};

TEST(CompleteGrid, ReconstructsAsTheSparseGridWhereEveryBlockIsInTheBand) {
    for (const Case& c : kCases) {
        SCOPED_TRACE(::testing::Message() << c.n[0] << "x" << c.n[1] << "x" << c.n[2] << " B "
                                          << c.B << " band " << c.band);
        const GridShape s = testing::shapeOverUnitCube(c.n[0], c.n[1], c.n[2]);
        const std::vector<float> f =
            testing::bumpySphere(s, Vec3(0.1f, -0.05f, 0.0f), 0.55f, 0.04f);
        const Grid sparse = Grid::sparseFromDense(s, f, c.B, c.band);
        size_t inside, outside, surface;
        sparse.blockCounts(inside, outside, surface);
        ASSERT_EQ(inside + outside, 0u) << "the band must hold every block for this comparison";
        const Grid complete = Grid::completeFromDense(s, f, c.B, c.band);
        EXPECT_TRUE(complete.isComplete());
        EXPECT_FALSE(sparse.isComplete());
        EXPECT_EQ(complete.surfaceBlockCount(), surface);
        expectSameField(sparse, complete);
    }
}

TEST(CompleteGrid, ARefreshIsTheGridBuiltAfreshFromTheSameSamples) {
    for (const Case& c : kCases) {
        SCOPED_TRACE(::testing::Message()
                     << c.n[0] << "x" << c.n[1] << "x" << c.n[2] << " B " << c.B);
        const GridShape s = testing::shapeOverUnitCube(c.n[0], c.n[1], c.n[2]);
        const Grid first = Grid::completeFromDense(
            s, testing::bumpySphere(s, Vec3(0.1f, -0.05f, 0.0f), 0.55f, 0.04f), c.B, c.band);
        // A moved surface, and a field whose far faces are one value (where sparseFromDense
        // would share a constant apron block: the complete layout keeps them private).
        std::vector<float> moved = testing::bumpySphere(s, Vec3(-0.2f, 0.1f, 0.15f), 0.4f, 0.08f);
        std::vector<float> flat(s.vertexCount());
        for (size_t i = 0; i < flat.size(); ++i) flat[i] = i % 7 == 0 ? -0.3f : 0.25f;
        for (int k = 0; k <= s.cells[2]; ++k)
            for (int j = 0; j <= s.cells[1]; ++j)
                for (int i = 0; i <= s.cells[0]; ++i)
                    if (i == s.cells[0] || j == s.cells[1] || k == s.cells[2])
                        flat[(static_cast<size_t>(k) * (s.cells[1] + 1) + j) * (s.cells[0] + 1) +
                             i] = 0.5f;
        for (const std::vector<float>* f : {&moved, &flat}) {
            const Grid refreshed = first.refreshComplete(*f);
            EXPECT_TRUE(refreshed.isComplete());
            expectSameArrays(refreshed, Grid::completeFromDense(s, *f, c.B, c.band));
            // And a second refresh, from the refreshed grid.
            expectSameArrays(refreshed.refreshComplete(moved),
                             Grid::completeFromDense(s, moved, c.B, c.band));
            if (c.band > 1e5f)
                expectSameField(refreshed, Grid::sparseFromDense(s, *f, c.B, c.band));
        }
    }
}

// The GPU refresh's skip distances (complete_skip.h's functions run in loops as its kernels run
// them: sources, 8 dilations of the padded blocks, the tiles' sources and their dilations) against
// Grid::computeBlockSkip's, on grids whose surface is small (most blocks and tiles far from it)
// and large.
TEST(CompleteGrid, SkipDistancesByDilationAreComputeBlockSkips) {
    struct Field {
        int n[3], B;
        float radius;
    };
    for (const Field c : {Field{{128, 128, 128}, 4, 0.08f}, Field{{150, 97, 121}, 4, 0.3f},
                          Field{{200, 90, 130}, 8, 0.12f}, Field{{40, 40, 40}, 4, 0.55f}}) {
        SCOPED_TRACE(::testing::Message() << c.n[0] << "x" << c.n[1] << "x" << c.n[2] << " B "
                                          << c.B << " r " << c.radius);
        const GridShape s = testing::shapeOverUnitCube(c.n[0], c.n[1], c.n[2]);
        const Grid grid = Grid::completeFromDense(
            s, testing::bumpySphere(s, Vec3(0.3f, -0.2f, 0.1f), c.radius, 0.01f), c.B, 1e6f);
        const GridView g = grid.view();
        const int px = g.tiles[0] * kTileBlocks, py = g.tiles[1] * kTileBlocks,
                  pz = g.tiles[2] * kTileBlocks;
        const size_t n = static_cast<size_t>(px) * py * pz;
        std::vector<uint8_t> d(n), next(n);
        auto forEach = [](int nx, int ny, int nz, auto&& f) {
            for (int z = 0; z < nz; ++z)
                for (int y = 0; y < ny; ++y)
                    for (int x = 0; x < nx; ++x)
                        f((static_cast<size_t>(z) * ny + y) * nx + x, x, y, z);
        };
        forEach(px, py, pz,
                [&](size_t i, int x, int y, int z) { d[i] = blockSkipSource(g, x, y, z); });
        for (int step = 0; step < kTileBlocks; ++step) {
            forEach(px, py, pz, [&](size_t i, int x, int y, int z) {
                next[i] = chebyshevStep(d.data(), px, py, pz, x, y, z);
            });
            d.swap(next);
        }
        std::vector<uint8_t> blockSkip(grid.blockSkip().size(), 1);
        forEach(px, py, pz, [&](size_t i, int x, int y, int z) {
            blockSkip[completePaddedSlot(g, x, y, z)] = d[i];
        });
        EXPECT_EQ(blockSkip, grid.blockSkip());
        const size_t tiles = grid.tileSkip().size();
        std::vector<uint16_t> t(tiles), tnext(tiles);
        forEach(g.tiles[0], g.tiles[1], g.tiles[2], [&](size_t i, int x, int y, int z) {
            t[i] = tileSkipSource(d.data(), px, py, x, y, z);
        });
        for (int step = 0; step < std::max(g.tiles[0], std::max(g.tiles[1], g.tiles[2])); ++step) {
            forEach(g.tiles[0], g.tiles[1], g.tiles[2], [&](size_t i, int x, int y, int z) {
                tnext[i] = chebyshevStep(t.data(), g.tiles[0], g.tiles[1], g.tiles[2], x, y, z);
            });
            t.swap(tnext);
        }
        std::vector<uint8_t> tileSkip(tiles);
        for (size_t i = 0; i < tiles; ++i) tileSkip[i] = tileSkipEntry(t[i]);
        EXPECT_EQ(tileSkip, grid.tileSkip());
        // The cases reach both caps: blocks 9 away and tiles without a source.
        EXPECT_TRUE(std::count(blockSkip.begin(), blockSkip.end(), kSkipFarBlocks) > 0 ||
                    c.radius > 0.5f);
    }
}

}  // namespace
}  // namespace sdft
