#include "sdftrace/field/block_table.h"

#include <gtest/gtest.h>

#include "sdftrace/core/error.h"
#include "sdftrace/field/grid.h"

namespace sdft {
namespace {

// 19 x 9 x 17 blocks (tiles cut by the grid's faces): outside, with an inside ball and a shell of
// surface blocks around it, and one far inside tile-sized region.
std::vector<uint8_t> ballFlags(const int n[3]) {
    std::vector<uint8_t> flags(static_cast<size_t>(n[0]) * n[1] * n[2]);
    for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
            for (int i = 0; i < n[0]; ++i) {
                const int r2 = (i - 5) * (i - 5) + (j - 4) * (j - 4) + (k - 5) * (k - 5);
                uint8_t f = r2 < 9 ? 1 : r2 < 16 ? 2 : 0;
                if (i >= 16 && k >= 8) f = 1;  // a whole tile (16..18, 8..15) and more inside
                flags[(static_cast<size_t>(k) * n[1] + j) * n[0] + i] = f;
            }
    return flags;
}

TEST(BlockTable, DenseFlagsRoundTripAndConstantTilesSharePages) {
    const int n[3] = {19, 9, 17};
    const std::vector<uint8_t> flags = ballFlags(n);
    const BlockTable t = BlockTable::fromDense(n, flags, "t");
    EXPECT_EQ(t.tiles[0], 3);
    EXPECT_EQ(t.tiles[1], 2);
    EXPECT_EQ(t.tiles[2], 3);
    EXPECT_EQ(t.dense(), flags);
    size_t surface = 0;
    for (uint8_t f : flags) surface += f == 2;
    EXPECT_EQ(t.surfaceBlocks(), surface);
    // Every lookup agrees with the flat flags.
    for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
            for (int i = 0; i < n[0]; ++i)
                ASSERT_EQ(t.flags[t.slot(i, j, k)],
                          flags[(static_cast<size_t>(k) * n[1] + j) * n[0] + i]);
    // Tiles of one flag own no page: tile (2, 0, 1) is all inside, (2, 0, 0) all outside.
    EXPECT_EQ(t.tilePage[(1 * 2 + 0) * 3 + 2], kInsidePage);
    EXPECT_EQ(t.tilePage[(0 * 2 + 0) * 3 + 2], kOutsidePage);
    EXPECT_LT(t.pages(), static_cast<size_t>(kFirstOwnPage + 18));
    const std::vector<int> own = t.ownTiles();
    EXPECT_EQ(own.size(), 3 * (t.pages() - kFirstOwnPage));
}

TEST(BlockTable, RejectsWrongCountsAndInvalidFlags) {
    const int n[3] = {19, 9, 17};
    std::vector<uint8_t> flags = ballFlags(n);
    flags.pop_back();
    EXPECT_THROW(BlockTable::fromDense(n, flags, "t"), InputError);
    flags = ballFlags(n);
    flags[1234] = 7;
    try {
        BlockTable::fromDense(n, flags, "file.sdfg");
        FAIL() << "an invalid flag was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("file.sdfg: block 1234 has an invalid flag 7"),
                  std::string::npos)
            << e.what();
    }
}

// A grid whose bounding box is large and whose surface is small keeps its per-block tables small:
// memory follows the own pages, not the block count.
TEST(BlockTable, MemoryFollowsTheSurface) {
    GridShape shape;
    for (int a = 0; a < 3; ++a) shape.cells[a] = 1024;
    shape.voxelSize = 1.0f / 1024;
    const int n[3] = {256, 256, 256};  // blocks of 4 cells
    BlockTable t = BlockTable::empty(n);
    // One own page: tile (3, 4, 5), a surface block at its first block.
    t.tilePage[(5 * 32 + 4) * 32 + 3] = kFirstOwnPage;
    t.flags.resize(3 * kPageEntries, 0);
    t.flags[2 * kPageEntries] = 2;
    std::vector<float> samples(125);
    for (int k = 0; k < 5; ++k)
        for (int j = 0; j < 5; ++j)
            for (int i = 0; i < 5; ++i) samples[(k * 5 + j) * 5 + i] = (i - 2.5f) / 1024;
    const Grid g = Grid::sparseFromTable(shape, 4, 2.0f / 1024, std::move(t), samples, "t");
    // 32^3 tiles of 6 bytes (page, skip distance, Lipschitz level), 3 pages of 7 bytes per entry,
    // one block's samples (its own and the apron's: no neighbour holds it), neighbour table and
    // mask.
    EXPECT_LE(g.blockSamples().size(), size_t{8 * 64});
    EXPECT_LT(g.memoryBytes(),
              size_t{32 * 32 * 32 * 6 + 3 * 512 * 7 + 8 * 64 * 4 + 8 * 4 + 64 + 64});
    size_t inside, outside, surface;
    g.blockCounts(inside, outside, surface);
    EXPECT_EQ(surface, 1u);
    EXPECT_EQ(inside, 0u);
    EXPECT_EQ(outside, size_t{256} * 256 * 256 - 1);
    const GridView v = g.view();
    EXPECT_EQ(v.vertex(3 * 32 + 1, 4 * 32, 5 * 32), (1 - 2.5f) / 1024);
    EXPECT_EQ(v.vertex(0, 0, 0), 2.0f / 1024);
    // The surface is found: bounds of the block's sign-changing cells.
    const Bounds3 b = g.surfaceBounds();
    EXPECT_FALSE(b.empty());
}

}  // namespace
}  // namespace sdft
