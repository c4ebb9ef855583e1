// The compiled tape against the recursive tree reference, batch against scalar, and the Lipschitz
// bound of every node kind on random point pairs.
#include "sdftrace/field/tape.h"

#include <gtest/gtest.h>

#include "sdftrace/exec/simd.h"
#include "sdftrace/field/test_util.h"
#include "sdftrace/field/transforms.h"

namespace sdft {
namespace {

TEST(Tape, MatchesTreeReferenceOnRandomPoints) {
    NodePtr root = testing::everyKindTree();
    Tape tape = compileTape(root, CompileOptions{.boundsCulling = false});
    testing::Rng rng(42);
    for (int i = 0; i < 20000; ++i) {
        Vec3 p = rng.inCube(4);
        float ref = evalTree(*root, p);
        ASSERT_NEAR(tape.eval(p), ref, 1e-5f * (1 + std::fabs(ref))) << i;
    }
}

// Decision 0002: culling returns the running minimum instead of an operand whose box is no nearer.
// For exact-distance operands that is the same value; for any operands the sign (the surface) is
// unchanged and the value never drops below the exact tape's.
TEST(Tape, BoundsCullingIsExactForExactOperandsAndKeepsTheSurfaceOtherwise) {
    using namespace node;
    std::vector<NodePtr> exact;
    testing::Rng rng(44);
    for (int i = 0; i < 30; ++i) {
        Vec3 c = rng.inCube(3);
        NodePtr shape =
            i % 3 == 0 ? sphere(0.3f) : (i % 3 == 1 ? box({0.2f, 0.3f, 0.1f}) : torus(0.3f, 0.1f));
        exact.push_back(translate(rotate(shape, rotationAxisAngle(rng.direction(), 40)), c));
    }
    NodePtr exactUnion = unite(exact);
    Tape culled = compileTape(exactUnion),
         plain = compileTape(exactUnion, {.boundsCulling = false});
    EXPECT_EQ(culled.numCulls(), 29);
    for (int i = 0; i < 20000; ++i) {
        Vec3 p = rng.inCube(5);
        ASSERT_NEAR(culled.eval(p), plain.eval(p), 1e-6f);
    }
    NodePtr any = testing::everyKindTree();
    Tape culledAny = compileTape(any), plainAny = compileTape(any, {.boundsCulling = false});
    for (int i = 0; i < 20000; ++i) {
        Vec3 p = rng.inCube(5);
        float a = culledAny.eval(p), b = plainAny.eval(p);
        ASSERT_GE(a, b - 1e-6f);
        ASSERT_EQ(a < 0, b < 0);
    }
}

TEST(Tape, BatchMatchesScalar) {
    NodePtr root = testing::everyKindTree();
    Tape tape = compileTape(root);
    testing::Rng rng(43);
    const int n = 1000;  // not a multiple of the batch width on purpose
    std::vector<float> x(n), y(n), z(n), out(n);
    for (int i = 0; i < n; ++i) {
        Vec3 p = rng.inCube(4);
        x[i] = p.x, y[i] = p.y, z[i] = p.z;
    }
    // Both builds of the batch loop (exec/simd.h): the same values as the scalar path.
    const SimdLevel was = simdLevel();
    for (SimdLevel level : {SimdLevel::Baseline, SimdLevel::Avx2}) {
        if (setSimdLevel(level) != level) continue;  // a CPU without AVX2
        BatchScratch scratch;
        tape.evalBatch(x.data(), y.data(), z.data(), out.data(), n, scratch);
        for (int i = 0; i < n; ++i)
            ASSERT_EQ(out[i], tape.eval({x[i], y[i], z[i]})) << i << " " << simdLevelName(level);
    }
    setSimdLevel(was);
}

TEST(Tape, RecyclesRegisters) {
    // A union of 200 spheres needs two scalar registers, not 200.
    std::vector<NodePtr> spheres;
    for (int i = 0; i < 200; ++i)
        spheres.push_back(node::translate(node::sphere(0.1f), {0.3f * i, 0, 0}));
    // (Pruning off: its tape for points outside the cells is a hierarchy of unions.)
    Tape tape = compileTape(node::unite(spheres), {.pruning = false});
    EXPECT_LE(tape.numScalarRegs(), 2);
    EXPECT_LE(tape.numPointRegs(), 2);
    EXPECT_NEAR(tape.eval({0.3f * 57, 0.5f, 0}), 0.4f, 1e-5f);
}

TEST(Tape, MaterialFollowsTheNearestSurfaceAndBlends) {
    NodePtr a = node::withMaterial(node::translate(node::sphere(0.5f), {-1, 0, 0}), 1);
    NodePtr b = node::withMaterial(node::translate(node::sphere(0.5f), {1, 0, 0}), 2);
    Tape hard = compileTape(node::unite({a, b}));
    EXPECT_EQ(hard.evalMaterial({-1.5f, 0, 0}).id[0], 1);
    EXPECT_EQ(hard.evalMaterial({1.5f, 0, 0}).id[0], 2);
    Tape smooth = compileTape(node::smoothUnion(a, b, 2.0f));
    MaterialBlend mid = smooth.evalMaterial({0, 0, 0});
    ASSERT_EQ(mid.count, 2);
    EXPECT_NEAR(mid.weight[0], 0.5f, 1e-5f);
    EXPECT_NEAR(mid.weight[0] + mid.weight[1], 1.0f, 1e-6f);
}

// Textures live in the frame of the node that assigned the material: the blend carries the point
// there, inside that node's transforms (and the outer ones), but not the transforms below it.
TEST(Tape, MaterialCarriesThePointInTheMaterialsFrame) {
    const Mat3 R = rotationAxisAngle(normalize(Vec3(1, 2, 3)), 40.0f);
    // translate(rotate(scale(material(union(sphere, translate(box))))))
    NodePtr inner =
        node::unite({node::sphere(0.5f), node::translate(node::box(Vec3(0.2f)), Vec3(0.6f, 0, 0))});
    NodePtr object = node::translate(
        node::rotate(node::scale(node::withMaterial(inner, 3), Vec3(2.0f)), R), {1, -2, 0.5f});
    Tape tape = compileTape(node::unite({object, node::withMaterial(node::sphere(0.1f), 1)}));
    testing::Rng rng(99);
    int checked = 0;
    for (int i = 0; i < 200; ++i) {
        const Vec3 p = Vec3(1, -2, 0.5f) + rng.inCube(1.2f);
        const MaterialBlend b = tape.evalMaterial(p);
        if (b.id[0] != 3) continue;
        ++checked;
        // The object's frame: undo translate, rotate (R^T), scale.
        const Vec3 q = p - Vec3(1, -2, 0.5f);
        const Vec3 expected = (R.transposed() * q) / 2.0f;
        for (int a = 0; a < 3; ++a) ASSERT_NEAR(b.local[0][a], expected[a], 1e-5f) << i;
    }
    EXPECT_GT(checked, 100);
}

// |f(a) - f(b)| <= L |a - b| on random pairs, far apart and very close (local slope).
void expectLipschitz(const NodePtr& n, const char* what, uint32_t seed) {
    // The field's definition, without the culling shortcut (which is discontinuous by design).
    Tape tape = compileTape(n, CompileOptions{.boundsCulling = false});
    float L = tape.lipschitz();
    testing::Rng rng(seed);
    float worst = 0;
    for (int i = 0; i < 20000; ++i) {
        Vec3 a = rng.inCube(3);
        Vec3 b = (i % 2) ? rng.inCube(3) : a + rng.direction() * rng.uniform(1e-3f, 2e-2f);
        float dist = length(a - b);
        if (dist < 1e-4f) continue;
        float slope = std::fabs(tape.eval(a) - tape.eval(b)) / dist;
        worst = std::fmax(worst, slope);
    }
    // float rounding of the difference quotient over short pairs
    EXPECT_LE(worst, L * 1.002f + 1e-3f) << what << ": measured slope " << worst << " > L = " << L;
}

TEST(Lipschitz, BoundHoldsForEveryPrimitiveOperatorAndTransform) {
    using namespace node;
    NodePtr s = sphere(0.5f), bx = box({0.4f, 0.6f, 0.3f});
    struct {
        const char* name;
        NodePtr node;
    } cases[] = {
        {"sphere", s},
        {"box", bx},
        {"round_box", roundBox({0.5f, 0.5f, 0.5f}, 0.2f)},
        {"torus", torus(0.7f, 0.2f)},
        {"capsule", capsule({-1, 0, 0}, {1, 0.5f, 0}, 0.3f)},
        {"cylinder", cylinder(0.5f, 0.8f)},
        {"cone", cone(0.5f, 1.2f)},
        {"plane", plane({1, 2, 3}, 0.5f)},
        {"ellipsoid", ellipsoid({1.0f, 0.2f, 0.5f})},
        {"octahedron", octahedron(0.8f)},
        {"dodecahedron", dodecahedron(0.6f)},
        {"blobs", blobs({{{0, 0, 0}, 0.7f, 1}, {{0.5f, 0, 0}, 0.4f, 2}}, 0.5f)},
        {"union", unite({s, translate(bx, {1, 0, 0})})},
        {"intersection", intersect({s, bx})},
        {"difference", subtract(bx, s)},
        {"complement", complement(s)},
        {"smooth_union", smoothUnion(s, translate(bx, {0.5f, 0, 0}), 0.5f)},
        {"smooth_intersection", smoothIntersection(s, bx, 0.3f)},
        {"smooth_difference", smoothDifference(bx, s, 0.3f)},
        {"morph", morph(s, torus(0.6f, 0.2f), 0.4f)},
        {"translate", translate(bx, {0.3f, -0.2f, 1})},
        {"rotate", rotate(bx, rotationAxisAngle({1, 2, 0}, 40))},
        {"uniform scale", scale(bx, Vec3(2.5f))},
        {"non-uniform scale", scale(s, {3.0f, 0.5f, 1.0f})},
        {"repeat", repeat(s, {1.2f, 1.5f, 1.1f}, {2, 1, 0})},
        {"displace", displace(s, 0.1f, 4.0f, 4, 0.5f)},
        {"nested", testing::everyKindTree()},
    };
    uint32_t seed = 1;
    for (const auto& c : cases) expectLipschitz(c.node, c.name, seed++);
}

TEST(Lipschitz, NonUniformScaleIsCorrectedToStayADistanceBound) {
    // Liktor §2.2: without the min(s) factor, a sphere stretched 4x along x would report
    // f = |p/s| - r, too large along y/z by a factor 4 and unsafe to step by.
    NodePtr n = node::scale(node::sphere(1.0f), {4.0f, 1.0f, 1.0f});
    Tape tape = compileTape(n);
    // Along y the true distance from (0, 3, 0) to the surface (y = 1) is 2.
    EXPECT_LE(tape.eval({0, 3, 0}), 2.0f + 1e-5f);
    // Along x the true distance from (6, 0, 0) to the surface (x = 4) is 2; the bound is below it.
    EXPECT_LE(tape.eval({6, 0, 0}), 2.0f + 1e-5f);
    EXPECT_GT(tape.eval({6, 0, 0}), 0.0f);
}

TEST(Bounds, RepeatAndTransformsContainTheSurface) {
    NodePtr root = testing::everyKindTree();
    Bounds3 b = nodeBounds(*root);
    testing::Rng rng(5);
    for (int i = 0; i < 50000; ++i) {
        Vec3 p = rng.inCube(6);
        if (evalTree(*root, p) < 0 && p.y > -2.9f) {
            ASSERT_TRUE(b.contains(p));
        }
    }
}

}  // namespace
}  // namespace sdft

namespace sdft {
namespace {

// The property bounds culling of smooth unions relies on: outside its bounds, a node that claims to
// dominate them has a value at least the distance to them.
TEST(Bounds, DominatingNodesAreAtLeastTheirBoxDistance) {
    using namespace node;
    NodePtr exacts =
        unite({translate(sphere(0.4f), {1, 0, 0}),
               rotate(box({0.3f, 0.5f, 0.2f}), rotationAxisAngle({1, 1, 1}, 30)), torus(0.5f, 0.1f),
               capsule({0, 0, 0}, {0.5f, 0.5f, 0}, 0.1f), cone(0.3f, 0.6f), cylinder(0.2f, 0.4f),
               roundBox({0.3f, 0.3f, 0.3f}, 0.1f)});
    std::vector<NodePtr> claims = {
        exacts,
        smoothUnion(sphere(0.5f), translate(box({0.3f, 0.3f, 0.3f}), {0.6f, 0, 0}), 0.4f),
        subtract(box({0.5f, 0.5f, 0.5f}), sphere(0.6f)),
        smoothDifference(torus(0.6f, 0.2f), sphere(0.3f), 0.1f),
        scale(exacts, Vec3(1.7f)),
        repeat(sphere(0.2f), {0.6f, 0.6f, 0.6f}, {2, 1, 0}),
        blobs({{{0, 0, 0}, 0.7f, 1}, {{0.5f, 0.2f, 0}, 0.4f, 1}}, 0.5f),
    };
    std::vector<NodePtr> nonClaims = {ellipsoid({1, 0.2f, 0.3f}),
                                      octahedron(0.5f),
                                      dodecahedron(0.4f),
                                      scale(sphere(0.5f), {2, 1, 1}),
                                      morph(sphere(0.5f), box(Vec3(0.4f)), 0.5f),
                                      displace(sphere(0.5f), 0.1f, 3, 2, 0.5f)};
    for (const NodePtr& n : nonClaims) EXPECT_FALSE(dominatesBounds(*n)) << nodeKindName(n->kind);
    testing::Rng rng(31);
    for (const NodePtr& n : claims) {
        ASSERT_TRUE(dominatesBounds(*n)) << nodeKindName(n->kind);
        Bounds3 b = nodeBounds(*n);
        float k[6] = {b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z};
        for (int i = 0; i < 20000; ++i) {
            Vec3 p = rng.inCube(4);
            float d = xform::boxDistance(p, k);
            if (d > 0) {
                ASSERT_GE(evalTree(*n, p), d - 1e-5f) << nodeKindName(n->kind);
            }
        }
    }
}

TEST(Tape, SmoothUnionCullingIsExactForDominatingOperands) {
    using namespace node;
    testing::Rng rng(45);
    NodePtr chain = sphere(0.3f);
    for (int i = 0; i < 40; ++i) {
        NodePtr shape = i % 2 ? torus(0.25f, 0.08f) : roundBox({0.2f, 0.2f, 0.2f}, 0.05f);
        chain = smoothUnion(
            chain,
            translate(rotate(shape, rotationAxisAngle(rng.direction(), 50)), rng.inCube(2.5f)),
            0.3f);
    }
    Tape culled = compileTape(chain), plain = compileTape(chain, {.boundsCulling = false});
    EXPECT_EQ(culled.numCulls(), 40);
    std::vector<float> x(4096), y(4096), z(4096), out(4096);
    for (int i = 0; i < 4096; ++i) {
        Vec3 p = rng.inCube(4);
        x[i] = p.x, y[i] = p.y, z[i] = p.z;
        ASSERT_NEAR(culled.eval(p), plain.eval(p), 1e-6f);
        ASSERT_EQ(culled.evalMaterial(p).id[0], plain.evalMaterial(p).id[0]);
    }
    BatchScratch scratch;
    culled.evalBatch(x.data(), y.data(), z.data(), out.data(), 4096, scratch);
    for (int i = 0; i < 4096; ++i) ASSERT_EQ(out[i], culled.eval({x[i], y[i], z[i]}));
}

}  // namespace
}  // namespace sdft
