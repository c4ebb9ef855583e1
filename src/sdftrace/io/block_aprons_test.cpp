#include "block_aprons.h"

#include <gtest/gtest.h>

#include "sdftrace/core/error.h"
#include "sdftrace/field/node.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/tape.h"

namespace sdft {
namespace {

Grid sphereGrid(int blockSize) {
    Tape tape = compileTape(node::sphere(1.0f), {.boundsCulling = false});
    SampleOptions o;
    o.resolution = 40;
    o.blockSize = blockSize;
    return sampleGrid(tape, tape.bounds(), o);
}

// The grid's own two-level table.
BlockTable tableOf(const Grid& g) {
    BlockTable t;
    const GridView v = g.view();
    for (int a = 0; a < 3; ++a) t.blocks[a] = v.blocks[a], t.tiles[a] = v.tiles[a];
    t.tilePage = g.tilePage();
    t.flags = g.flags();
    return t;
}

TEST(BlockAprons, SplitAndJoinGiveTheSameSamples) {
    for (int B : {4, 8}) {
        const Grid g = sphereGrid(B);
        const SplitBlocks split = splitBlocks(g);
        const size_t surface = g.surfaceBlockCount();
        EXPECT_EQ(split.own.size(), surface * B * B * B);
        // Most aprons are shared with a surface neighbour: far fewer kept than stored.
        EXPECT_LT(split.explicitly.size(), surface * apronSize(B) / 2) << B;
        EXPECT_EQ(joinBlocks(g.shape(), B, tableOf(g), split, "t"), g.expandedBlockSamples()) << B;
    }
}

TEST(BlockAprons, ApronsThatDisagreeWithTheirOwnerAreKept) {
    const Grid g = sphereGrid(4);
    // Perturb every block's last sample (its +x+y+z corner, owned by a neighbour).
    std::vector<float> samples = g.expandedBlockSamples();
    for (size_t i = 124; i < samples.size(); i += 125) samples[i] += 1e-3f;
    const Grid changed =
        Grid::sparseFromBuffers(g.shape(), 4, g.background(), g.denseFlags(), samples, "t");
    const SplitBlocks split = splitBlocks(changed);
    EXPECT_GE(split.explicitly.size(), samples.size() / 125);
    EXPECT_EQ(joinBlocks(changed.shape(), 4, tableOf(changed), split, "t"), samples);
}

TEST(BlockAprons, InconsistentSplitsAreRejected) {
    const Grid g = sphereGrid(4);
    SplitBlocks split = splitBlocks(g);
    // A kept apron made implicit where its owner has no samples, or a count that does not add up.
    bool changed = false;
    for (size_t w = 0; w < split.masks.size() && !changed; ++w)
        if (split.masks[w]) {
            split.masks[w] &= split.masks[w] - 1;
            changed = true;
        }
    ASSERT_TRUE(changed);
    EXPECT_THROW(joinBlocks(g.shape(), 4, tableOf(g), split, "t"), InputError);
    SplitBlocks shortOwn = splitBlocks(g);
    shortOwn.own.pop_back();
    EXPECT_THROW(joinBlocks(g.shape(), 4, tableOf(g), shortOwn, "t"), InputError);
}

}  // namespace
}  // namespace sdft
