#include "sdftrace/render/ambient_occlusion.h"

#include <gtest/gtest.h>

#include "sdftrace/field/node.h"

namespace sdft {
namespace {

// Over an open floor nothing occludes; towards the corner with a wall the occlusion grows
// steadily; values stay in [0, 1].
TEST(AmbientOcclusion, OpenFloorIsUnoccludedAndCornersDarken) {
    // Floor y <= 0 and a wall x >= 1.
    Tape tape = compileTape(
        node::unite({node::plane(Vec3(0, 1, 0), 0.0f), node::plane(Vec3(-1, 0, 0), -1.0f)}));
    AmbientOcclusionOptions o;
    EXPECT_FLOAT_EQ(ambientOcclusion(tape, Vec3(-5, 0, 0), Vec3(0, 1, 0), o).ao, 1.0f);
    float prev = 2;
    for (float x = -1.0f; x <= 0.999f; x += 0.1f) {
        const AmbientOcclusionResult r = ambientOcclusion(tape, Vec3(x, 0, 0), Vec3(0, 1, 0), o);
        EXPECT_EQ(r.evaluations, o.samples);
        EXPECT_GE(r.ao, 0.0f);
        EXPECT_LE(r.ao, prev + 1e-6f) << x;
        prev = r.ao;
    }
    EXPECT_LT(prev, 0.1f);  // in the corner
}

}  // namespace
}  // namespace sdft
