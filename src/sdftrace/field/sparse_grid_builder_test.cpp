#include "sdftrace/field/sparse_grid_builder.h"

#include <gtest/gtest.h>

#include <limits>

#include "sdftrace/core/error.h"
#include "sdftrace/field/node.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/field/test_grid_fields.h"

namespace sdft {
namespace {

Grid torusGrid(int blockSize) {
    Tape tape = compileTape(node::torus(0.7f, 0.2f), {.boundsCulling = false});
    SampleOptions o;
    o.resolution = 40;
    o.blockSize = blockSize;
    return sampleGrid(tape, tape.bounds(), o);
}

using testing::tableOf;

StoredSparse partsOf(const Grid& g) {
    return {g.blockSamples(),  g.blockNeighbors(), g.apronFrom(),      g.apronCode(),
            g.cellMasks(),     g.blockSkip(),      g.blockLipschitz(), g.tileSkip(),
            g.tileLipschitz(), g.lipschitz(),      g.gentleLipschitz()};
}

Grid fromParts(const Grid& g, StoredSparse parts) {
    SparseGridBuilder b(g.shape(), g.blockSize(), g.background(), tableOf(g), "t", false);
    return b.fromStored(std::move(parts), "t");
}

// A grid from its stored blocks and tables (.sdfg version 5) is the grid; every index and code
// that the views follow is checked, so a damaged one is an InputError, not a read out of bounds.
TEST(SparseGridBuilder, StoredPartsGiveTheGridAndAreCheckedIndexByIndex) {
    for (int B : {4, 8}) {
        const Grid g = torusGrid(B);
        const Grid back = fromParts(g, partsOf(g));
        EXPECT_EQ(back.expandedBlockSamples(), g.expandedBlockSamples()) << B;
        EXPECT_EQ(back.cellMasks(), g.cellMasks()) << B;
        EXPECT_EQ(back.blockSkip(), g.blockSkip()) << B;
        EXPECT_EQ(back.memoryBytes(), g.memoryBytes()) << B;
        EXPECT_EQ(back.lipschitz(), g.lipschitz()) << B;
        const GridView a = g.view(), b = back.view();
        const Vec3 c = g.shape().bounds().center();
        EXPECT_EQ(a.interpolate(c + Vec3(0.7f, 0.01f, 0)), b.interpolate(c + Vec3(0.7f, 0.01f, 0)));
    }
    const Grid g = torusGrid(4);
    auto rejected = [&](auto&& damage) {
        StoredSparse p = partsOf(g);
        damage(p);
        EXPECT_THROW(fromParts(g, std::move(p)), InputError);
    };
    rejected([](StoredSparse& p) { p.blockNeighbors[9] = -1; });
    rejected([&](StoredSparse& p) {
        p.blockNeighbors[10] = static_cast<int32_t>(p.blockSamples.size());
    });
    rejected([](StoredSparse& p) { p.blockNeighbors[8] = 0; });  // block 1's own entry
    rejected([](StoredSparse& p) { p.blockLipschitz.back() = 2; });
    rejected([](StoredSparse& p) { p.tileLipschitz.front() = 7; });
    rejected([](StoredSparse& p) { p.cellMasks.pop_back(); });
    rejected([](StoredSparse& p) { p.blockSkip.push_back(1); });
    rejected([](StoredSparse& p) { p.blockSamples[3] = std::numeric_limits<float>::quiet_NaN(); });
    rejected([](StoredSparse& p) { p.lipschitz = 0.5f; });
    rejected([](StoredSparse& p) { p.gentleLipschitz = p.lipschitz * 2; });
    if (!g.apronFrom().empty()) {
        rejected([](StoredSparse& p) { p.apronCode[0] = 9; });
        rejected(
            [&](StoredSparse& p) { p.apronFrom[0] = static_cast<int32_t>(g.surfaceBlockCount()); });
    }
}

}  // namespace
}  // namespace sdft
