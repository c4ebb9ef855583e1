// Segment bounds (tape_segment.h): on every kind of node, on repeated, culled and pruned tapes,
// the slope bounds the field's change along the segment it reports, the value is the point
// evaluator's, and the bound is tight where the rules say it is (planes, spheres, boxes, far
// union operands dropped).
#include "sdftrace/field/tape_segment.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "sdftrace/field/random_scenes.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/field/test_util.h"

namespace sdft {
namespace {

using testing::Rng;

// Random segments from points in (and around) the scene's box, with random and horizontal
// directions (grazing the floors), of lengths from a hair to across the scene.
struct Segments {
    Rng rng;
    Bounds3 box;
    int i = 0;
    // The next segment's start p and direction u, and its bound through `view`.
    SegmentBound next(const TapeView& view, Vec3& p, Vec3& u) {
        p = rng.inBox(box.lo, box.hi);
        u = rng.direction();
        if (i % 3 == 0) u = normalize(Vec3(u.x, 0.02f * u.y, u.z));
        const float len = std::array{0.02f, 0.3f, 2.0f, 50.0f}[i % 4];
        ++i;
        const SegmentBound b = evalTapeSegment(view, p, u, len);
        EXPECT_GE(b.length, 0.0f);
        EXPECT_LE(b.length, len);
        return b;
    }
};

// Without bounds culling the segment's value is the field's, and the slope bounds the field's
// change along the segment it reports, from the start and between neighbouring samples.
void expectSlopesBound(const NodePtr& root, bool pruning, uint32_t seed, Bounds3 box) {
    const Tape tape = compileTape(root, {.boundsCulling = false, .pruning = pruning});
    const Tape exact = compileTape(root, {.boundsCulling = false, .pruning = false});
    ASSERT_EQ(tape.pruned() != nullptr, pruning);
    const TapeView view = tape.view();
    Segments segments{Rng(seed), box};
    int tight = 0;
    for (int i = 0; i < 3000; ++i) {
        Vec3 p, u;
        const SegmentBound b = segments.next(view, p, u);
        const float f0 = exact.eval(p);
        ASSERT_NEAR(b.value, f0, 1e-5f * (1 + std::fabs(f0))) << "segment " << i;
        ASSERT_LE(b.slope, tape.lipschitz() * 1.0001f) << "segment " << i;
        tight += b.slope < 0.5f * tape.lipschitz();
        float prevS = 0, prevF = f0;
        for (int j = 1; j <= 24; ++j) {
            const float s = b.length * static_cast<float>(j) / 24.0f;
            const float f = exact.eval(p + u * s);
            const float tol = 2e-5f * (1 + std::fabs(f) + std::fabs(f0));
            ASSERT_LE(std::fabs(f - f0), b.slope * s * 1.0001f + tol)
                << "segment " << i << " at s = " << s << " of " << b.length;
            ASSERT_LE(std::fabs(f - prevF), b.slope * (s - prevS) * 1.0001f + tol)
                << "segment " << i << " at s = " << s;
            prevS = s;
            prevF = f;
        }
    }
    // The bound is worth having: a share of the segments are far under the global one (fewer in
    // repeated scenes, where the primitives take the global bound).
    EXPECT_GT(tight, 100);
}

// With bounds culling (decision 0002) the segment's value is the point evaluator's, which may
// exceed the field where a skipped operand's value is a loose bound; the step it allows,
// |f| / slope within the segment (which ends where a skipped operand could matter), never
// reaches the surface: the field keeps its sign there.
void expectCulledStepsSafe(const NodePtr& root, uint32_t seed, Bounds3 box) {
    const Tape tape = compileTape(root);
    const Tape exact = compileTape(root, {.boundsCulling = false, .pruning = false});
    const TapeView view = tape.view();
    Segments segments{Rng(seed), box};
    for (int i = 0; i < 3000; ++i) {
        Vec3 p, u;
        const SegmentBound b = segments.next(view, p, u);
        const float f0 = exact.eval(p);
        ASSERT_EQ(b.value, tape.eval(p)) << "segment " << i << ": culled as the point is";
        if (f0 <= 1e-4f) continue;  // rays march from outside
        const float step = b.slope > 0 ? std::fmin(b.value / b.slope, b.length) : b.length;
        for (int j = 1; j <= 24; ++j) {
            const float s = step * static_cast<float>(j) / 24.0f;
            ASSERT_GT(exact.eval(p + u * s), -2e-5f * (1 + f0))
                << "segment " << i << " at s = " << s << " of a step of " << step;
        }
    }
}

TEST(SegmentBound, BoundsTheFieldAlongSegmentsOfEveryKindOfNode) {
    const Bounds3 box{Vec3(-4, -3.5f, -4.5f), Vec3(4, 4, 4)};
    expectSlopesBound(testing::everyKindTree(), false, 1, box);
    expectCulledStepsSafe(testing::everyKindTree(), 2, box);
}

TEST(SegmentBound, BoundsTheFieldAlongSegmentsOfRepeatedRotatedAndScaledScenes) {
    using namespace node;
    NodePtr block = translate(box({0.25f, 0.6f, 0.25f}), {0, 0.6f, 0});
    NodePtr city = unite({repeat(block, {0.8f, 2.0f, 0.8f}, {4, 0, 4}), plane({0, 1, 0}, 0.0f),
                          rotate(scale(roundBox({0.5f, 0.2f, 0.3f}, 0.05f), {1.5f, 0.7f, 1.0f}),
                                 rotationAxisAngle({0.3f, 1, 0.2f}, 40)),
                          smoothUnion(translate(sphere(0.4f), {0, 1.6f, 0}),
                                      translate(sphere(0.3f), {0.4f, 1.7f, 0}), 0.2f)});
    expectSlopesBound(city, false, 3, {Vec3(-4, -0.5f, -4), Vec3(4, 3, 4)});
    expectCulledStepsSafe(city, 4, {Vec3(-4, -0.5f, -4), Vec3(4, 3, 4)});
}

TEST(SegmentBound, BoundsTheFieldAlongSegmentsThroughPrunedCells) {
    Rng rng(5);
    const NodePtr root = testing::randomScene(rng, 300, true);
    const Tape tape = compileTape(root);
    ASSERT_NE(tape.pruned(), nullptr);
    const Bounds3 box = tape.pruned()->box;
    expectSlopesBound(root, true, 5, {box.lo - Vec3(1), box.hi + Vec3(1)});
    expectCulledStepsSafe(root, 6, {box.lo - Vec3(1), box.hi + Vec3(1)});
    // Segments stop where their cell does (its tape holds only there).
    const TapeView view = tape.view();
    int clipped = 0;
    for (int i = 0; i < 500; ++i) {
        const Vec3 p = rng.inBox(box.lo, box.hi);
        const SegmentBound b = evalTapeSegment(view, p, rng.direction(), 100.0f);
        ASSERT_LE(b.length, maxComponent(box.extent()));
        clipped += b.length < 100.0f;
    }
    EXPECT_EQ(clipped, 500);
}

// The rules are exact where they can be: a plane's slope is the cosine of the ray's angle to its
// normal; a sphere's, on a segment ending where the ray passes closest, is 0 from that end's side;
// a box's, along a wall, is the direction's component across it; a union's is the operand that
// can be the minimum.
TEST(SegmentBound, IsTightForPlanesSpheresBoxesAndFarUnionOperands) {
    using namespace node;
    const Tape plane = compileTape(node::plane({0, 1, 0}, 0.0f));
    const Vec3 u = normalize(Vec3(1, -0.1f, 0));
    EXPECT_NEAR(evalTapeSegment(plane.view(), {0, 1, 0}, u, 5).slope,
                0.1f / length(Vec3(1, 0.1f, 0)), 1e-6f);
    const Tape ball = compileTape(sphere(1.0f));
    // From (-3, 2, 0) along +x to x = 0, the derivative runs from 3/sqrt(13) down to 0.
    EXPECT_NEAR(evalTapeSegment(ball.view(), {-3, 2, 0}, {1, 0, 0}, 3).slope, 3 / std::sqrt(13.0f),
                1e-5f);
    EXPECT_NEAR(evalTapeSegment(ball.view(), {-3, 2, 0}, {1, 0, 0}, 6).slope, 3 / std::sqrt(13.0f),
                1e-5f);
    const Tape wall = compileTape(box({1, 1, 1}));
    // Beside the face x = 1, moving along it (and slightly towards it): only x counts.
    const Vec3 along = normalize(Vec3(-0.05f, 0, 1));
    EXPECT_NEAR(evalTapeSegment(wall.view(), {1.5f, 0, -0.5f}, along, 1).slope,
                0.05f / length(Vec3(0.05f, 0, 1)), 1e-6f);
    // A floor with a ball far to the side: a grazing segment keeps the floor's slope.
    const Tape scene =
        compileTape(unite({node::plane({0, 1, 0}, 0.0f), translate(sphere(1), {0, 1, 30})}));
    EXPECT_NEAR(evalTapeSegment(scene.view(), {0, 0.5f, 0}, u, 4).slope,
                0.1f / length(Vec3(1, 0.1f, 0)), 1e-6f);
}

}  // namespace
}  // namespace sdft
