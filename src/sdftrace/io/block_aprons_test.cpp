#include "block_aprons.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

#include "sdftrace/core/error.h"
#include "sdftrace/field/node.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/field/test_grid_fields.h"

namespace sdft {
namespace {

Grid sphereGrid(int blockSize) {
    Tape tape = compileTape(node::sphere(1.0f), {.boundsCulling = false});
    SampleOptions o;
    o.resolution = 40;
    o.blockSize = blockSize;
    return sampleGrid(tape, tape.bounds(), o);
}

using testing::tableOf;

// The grid again from its own samples (as a loader decompresses them into the builder) and the
// aprons `aprons`.
Grid rejoin(const Grid& g, const ApronSamples& aprons, float ownDelta = 0) {
    SparseGridBuilder builder(g.shape(), g.blockSize(), g.background(), tableOf(g), "t");
    const size_t own = g.surfaceBlockCount() * g.blockSize() * g.blockSize() * g.blockSize();
    for (size_t i = 0; i < own; ++i) builder.ownSamples()[i] = g.blockSamples()[i] + ownDelta;
    return joinAprons(builder, aprons, "t");
}

TEST(BlockAprons, SplitAndJoinGiveTheSameGrid) {
    for (int B : {4, 8}) {
        const Grid g = sphereGrid(B);
        const ApronSamples aprons = splitAprons(g);
        const size_t surface = g.surfaceBlockCount();
        EXPECT_EQ(aprons.masks.size(), surface * apronWords(B));
        // Most aprons are shared with a surface neighbour: far fewer kept than stored.
        EXPECT_LT(aprons.explicitly.size(), surface * apronSize(B) / 2) << B;
        const Grid back = rejoin(g, aprons);
        EXPECT_EQ(back.expandedBlockSamples(), g.expandedBlockSamples()) << B;
        EXPECT_EQ(back.blockSamples(), g.blockSamples()) << B;
        EXPECT_EQ(back.lipschitz(), g.lipschitz()) << B;
        EXPECT_EQ(back.memoryBytes(), g.memoryBytes()) << B;
        // Read in windows of a few samples, as a loader decompresses them piece by piece: the
        // windows follow each other, each within its size unless one block alone exceeds it.
        SparseGridBuilder builder(g.shape(), B, g.background(), tableOf(g), "t");
        std::copy(g.blockSamples().begin(), g.blockSamples().begin() + surface * B * B * B,
                  builder.ownSamples());
        uint64_t next = 0, calls = 0;
        std::vector<float> window;
        auto read = [&](uint64_t from, uint64_t to) {
            EXPECT_EQ(from, next);
            EXPECT_LE(to - from, std::max<uint64_t>(40, apronSize(B)));
            next = to;
            ++calls;
            window.assign(aprons.explicitly.begin() + static_cast<ptrdiff_t>(from),
                          aprons.explicitly.begin() + static_cast<ptrdiff_t>(to));
            return window.data();
        };
        const Grid windowed =
            joinAprons(builder, aprons.masks, aprons.explicitly.size(), read, 40, "t");
        EXPECT_EQ(next, aprons.explicitly.size());
        EXPECT_GT(calls, 10u);
        EXPECT_EQ(windowed.blockSamples(), g.blockSamples()) << B;
        EXPECT_EQ(windowed.cellMasks(), g.cellMasks()) << B;
    }
}

TEST(BlockAprons, ApronsThatDisagreeWithTheirOwnerAreKept) {
    const Grid g = sphereGrid(4);
    // Perturb every block's last sample (its +x+y+z corner, owned by a neighbour).
    std::vector<float> samples = g.expandedBlockSamples();
    for (size_t i = 124; i < samples.size(); i += 125) samples[i] += 1e-3f;
    const Grid changed =
        Grid::sparseFromBuffers(g.shape(), 4, g.background(), g.denseFlags(), samples, "t");
    const ApronSamples aprons = splitAprons(changed);
    EXPECT_GE(aprons.explicitly.size(), samples.size() / 125);
    EXPECT_EQ(rejoin(changed, aprons).expandedBlockSamples(), samples);
}

TEST(BlockAprons, InconsistentSplitsAreRejected) {
    const Grid g = sphereGrid(4);
    ApronSamples aprons = splitAprons(g);
    // A kept apron made implicit where its owner has no samples, or a count that does not add up.
    bool changed = false;
    for (size_t w = 0; w < aprons.masks.size() && !changed; ++w)
        if (aprons.masks[w]) {
            aprons.masks[w] &= aprons.masks[w] - 1;
            changed = true;
        }
    ASSERT_TRUE(changed);
    EXPECT_THROW(rejoin(g, aprons), InputError);
    ApronSamples shortMasks = splitAprons(g);
    shortMasks.masks.pop_back();
    EXPECT_THROW(rejoin(g, shortMasks), InputError);
    ApronSamples extra = splitAprons(g);
    extra.explicitly.push_back(0.0f);
    EXPECT_THROW(rejoin(g, extra), InputError);
    // A sample that is not finite, among the own ones or the kept aprons.
    EXPECT_THROW(rejoin(g, splitAprons(g), std::numeric_limits<float>::infinity()), InputError);
    ApronSamples nan = splitAprons(g);
    ASSERT_FALSE(nan.explicitly.empty());
    nan.explicitly.back() = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(rejoin(g, nan), InputError);
}

}  // namespace
}  // namespace sdft
