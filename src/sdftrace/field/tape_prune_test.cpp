// Hierarchical pruning (tape_prune.h): the cells' tapes give the whole tape's values, scalar and
// batch, and its materials, on random scenes of many operands of every operator; traced hits stay
// where the whole tape puts them; the cells keep stretches of the whole tape as Runs; tapes too
// small to gain are left alone.
#include "sdftrace/field/tape_prune.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "sdftrace/exec/simd.h"
#include "sdftrace/field/node.h"
#include "sdftrace/field/random_scenes.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/field/test_util.h"
#include "sdftrace/math/camera.h"
#include "sdftrace/trace/field_tracer.h"

namespace sdft {
namespace {

using testing::Rng;

using testing::randomGroup;
using testing::randomScene;

TEST(Pruning, CellTapesGiveTheWholeTapesValuesOnRandomScenes) {
    Rng rng(44);
    for (int scene = 0; scene < 12; ++scene) {
        const NodePtr root = randomScene(rng, 60 + 30 * scene, scene % 2 == 0);
        const Tape whole = compileTape(root, {.boundsCulling = false, .pruning = false});
        const Tape pruned = compileTape(root, {.boundsCulling = false, .pruning = true});
        ASSERT_NE(pruned.pruned(), nullptr) << "scene " << scene;
        const PrunedTapes& p = *pruned.pruned();
        EXPECT_LT(p.instrs.size() / (p.spans.size() / 2), whole.size()) << "scene " << scene;
        const Bounds3 box = p.box;
        for (int i = 0; i < 3000; ++i) {
            // Mostly near the surfaces (where pruning is tight), some anywhere in the box.
            Vec3 q = rng.inBox(box.lo, box.hi);
            if (i % 3) q = q + rng.direction() * (0.01f - whole.eval(q)) * 0.5f;
            const float a = whole.eval(q), b = pruned.eval(q);
            // Exact, but for the one rounding of a smooth blend at weight 1.
            ASSERT_NEAR(a, b, 1e-5f * (std::fabs(a) + 1)) << "scene " << scene << " point " << i;
        }
    }
}

// Each cell's tape, as its instructions' fields.
std::vector<std::vector<uint64_t>> cellTapes(const Tape& t) {
    std::vector<std::vector<uint64_t>> out;
    const PrunedTapes& p = *t.pruned();
    for (const uint32_t id : p.cellTape) {
        std::vector<uint64_t>& fields = out.emplace_back();
        for (uint32_t j = 0; j < p.spans[2 * id + 1]; ++j) {
            const Instr& in = p.instrs[p.spans[2 * id] + j];
            fields.insert(fields.end(), {uint64_t(in.op), in.a, in.b, in.out, in.k, in.jump,
                                         uint64_t(uint32_t(in.cull))});
        }
    }
    return out;
}

// Random scenes of every operator, hard and smooth folds, each compiled twice (`before` sets up
// each build): both give every cell the same tape, instruction for instruction.
template <typename Setup>
void expectSameCells(uint32_t seed, Setup before) {
    Rng rng(seed);
    int pruned = 0;
    for (int scene = 0; scene < 6; ++scene) {
        const NodePtr root = randomScene(rng, 120 + 60 * scene, scene % 2 == 0);
        before(0);
        const Tape a = compileTape(root);
        before(1);
        const Tape b = compileTape(root);
        ASSERT_EQ(a.pruned() != nullptr, b.pruned() != nullptr) << "scene " << scene;
        if (!b.pruned()) continue;
        ++pruned;
        EXPECT_EQ(cellTapes(a), cellTapes(b)) << "scene " << scene;
    }
    EXPECT_GE(pruned, 4);
}

// The pruning pass is built twice (exec/simd.h).
TEST(Pruning, BothBuildsGiveTheSameCells) {
    if (!cpuHasAvx2()) GTEST_SKIP() << "this CPU has no AVX2";
    const SimdLevel was = simdLevel();
    expectSameCells(
        5, [](int build) { setSimdLevel(build == 0 ? SimdLevel::Baseline : SimdLevel::Avx2); });
    setSimdLevel(was);
}

// A node's leaf children compacted together from its tape, and each from a tape of its own.
TEST(Pruning, LeafTapesCompactedTogetherAsEachAlone) {
    const LeafCompaction was = setLeafCompaction(LeafCompaction::Lanes);
    for (const SimdLevel level : {SimdLevel::Baseline, SimdLevel::Avx2}) {
        const SimdLevel simd = setSimdLevel(level);
        expectSameCells(11, [](int build) {
            setLeafCompaction(build == 0 ? LeafCompaction::OneByOne : LeafCompaction::Lanes);
        });
        setSimdLevel(simd);
    }
    setLeafCompaction(was);
}

TEST(Pruning, BatchMatchesScalarAcrossCells) {
    Rng rng(7);
    const NodePtr root = randomScene(rng, 200, true);
    const Tape tape = compileTape(root);
    ASSERT_NE(tape.pruned(), nullptr);
    ASSERT_GE(tape.pruned()->outsideTape, 0);
    const Bounds3 box = tape.pruned()->box;
    std::vector<float> x, y, z;
    for (int i = 0; i < 1000; ++i) {
        // Runs of nearby points (one cell or a few) and scattered ones, some outside the box.
        const Vec3 q = i % 64 < 40 ? rng.inBox(box.lo, box.hi) + rng.inCube(0.05f) * float(i % 8)
                                   : rng.inBox(box.lo - Vec3(2), box.hi + Vec3(2));
        x.push_back(q.x);
        y.push_back(q.y);
        z.push_back(q.z);
    }
    std::vector<float> out(x.size());
    BatchScratch scratch;
    tape.evalBatch(x.data(), y.data(), z.data(), out.data(), static_cast<int>(x.size()), scratch);
    for (size_t i = 0; i < x.size(); ++i)
        ASSERT_EQ(out[i], tape.eval({x[i], y[i], z[i]})) << "point " << i;
}

// Sphere-traced hits with pruning (cells and the outside tape) where the whole tape has them,
// within 1e-4 t, from a camera above and one grazing the plane.
TEST(Pruning, HitsMatchTheWholeTape) {
    Rng rng(11);
    const NodePtr root = randomScene(rng, 300, true);
    const Tape whole = compileTape(root, {.pruning = false});
    const Tape pruned = compileTape(root);
    ASSERT_NE(pruned.pruned(), nullptr);
    for (const Vec3 eye : {Vec3(0, 8, 12), Vec3(-14, 0.4f, 3)}) {
        CameraDesc cd;
        cd.eye = eye;
        cd.target = {0, 0.3f, 0};
        cd.width = 96;
        cd.height = 64;
        const Camera cam(cd);
        std::vector<RaySegment> rays;
        for (int y = 0; y < cd.height; ++y)
            for (int x = 0; x < cd.width; ++x) rays.push_back({cam.pixelRay(x, y), 0, 200});
        for (const bool segmentTracing : {false, true}) {
            TraceOptions o;
            o.pixelRadius = cam.pixelRadius();
            if (segmentTracing) {
                // Segments end at the cells' faces, so the two marches sample other points; with
                // the screen-space exit a ray passing within half a pixel of a silhouette would
                // then hit in one and not the other. A fixed threshold keeps the hit sets alike.
                o.segmentTracing = true;
                o.screenSpace = false;
                o.tau = 1e-4f;
            }
            std::vector<TraceResult> a(rays.size()), b(rays.size());
            PacketScratch s;
            tracePacket(whole, rays, o, a, s);
            tracePacket(pruned, rays, o, b, s);
            int hits = 0, mismatches = 0;
            for (size_t i = 0; i < rays.size(); ++i) {
                if (!segmentTracing) ASSERT_EQ(a[i].hit, b[i].hit) << "ray " << i;
                if (a[i].hit != b[i].hit) ++mismatches;
                if (!a[i].hit || !b[i].hit) continue;
                ++hits;
                if (!segmentTracing) {  // the same values but for rounding, so the same march
                    ASSERT_NEAR(a[i].t, b[i].t, 1e-4f * a[i].t) << "ray " << i;
                    continue;
                }
                // The hits agree within 1e-4 t off the surface (along a grazing ray the root
                // refinement may stop short of the root by more than that along the ray).
                const Vec3 q = rays[i].ray.at(a[i].t);
                constexpr float h = 1e-3f;
                const Vec3 n =
                    normalize(Vec3(whole.eval(q + Vec3(h, 0, 0)) - whole.eval(q - Vec3(h, 0, 0)),
                                   whole.eval(q + Vec3(0, h, 0)) - whole.eval(q - Vec3(0, h, 0)),
                                   whole.eval(q + Vec3(0, 0, h)) - whole.eval(q - Vec3(0, 0, h))));
                ASSERT_LE(std::fabs((a[i].t - b[i].t) * dot(n, rays[i].ray.direction)),
                          1e-4f * a[i].t)
                    << "ray " << i;
            }
            EXPECT_LE(mismatches, static_cast<int>(rays.size()) / 200);
            EXPECT_GT(hits, static_cast<int>(rays.size()) / 4);
        }
    }
}

// The material at points near the surfaces (what shading reads) is the whole tape's: the same
// material dominates with the same weight, hard and smooth operators alike.
TEST(Pruning, CellTapesGiveTheWholeTapesMaterials) {
    Rng rng(19);
    std::vector<NodePtr> c{node::withMaterial(node::plane({0, 1, 0}, 0.1f), 0)};
    const float spread = 0.6f * std::sqrt(400.0f);
    for (int i = 0; i < 400; ++i)
        c.push_back(node::withMaterial(randomGroup(rng, spread), 1 + i % 5));
    const NodePtr root = node::unite(c);
    const Tape whole = compileTape(root, {.boundsCulling = false, .pruning = false});
    const Tape pruned = compileTape(root, {.boundsCulling = false, .pruning = true});
    ASSERT_NE(pruned.pruned(), nullptr);
    auto dominant = [](const MaterialBlend& m) {
        int best = 0;
        for (int i = 1; i < m.count; ++i)
            if (m.weight[i] > m.weight[best]) best = i;
        return best;
    };
    const Bounds3 box = pruned.pruned()->box;
    int checked = 0;
    for (int i = 0; i < 3000 && checked < 1000; ++i) {
        Vec3 q = rng.inBox(box.lo, box.hi);
        for (int step = 0; step < 2; ++step) {  // towards the surface along the gradient
            constexpr float h = 1e-3f;
            const Vec3 g(whole.eval(q + Vec3(h, 0, 0)) - whole.eval(q - Vec3(h, 0, 0)),
                         whole.eval(q + Vec3(0, h, 0)) - whole.eval(q - Vec3(0, h, 0)),
                         whole.eval(q + Vec3(0, 0, h)) - whole.eval(q - Vec3(0, 0, h)));
            if (!(length(g) > 0)) break;
            q = q - normalize(g) * whole.eval(q);
        }
        if (std::fabs(whole.eval(q)) > 0.05f) continue;
        ++checked;
        const MaterialBlend a = whole.evalMaterial(q), b = pruned.evalMaterial(q);
        ASSERT_GT(a.count, 0);
        ASSERT_GT(b.count, 0);
        const int da = dominant(a), db = dominant(b);
        ASSERT_EQ(a.id[da], b.id[db]) << "point " << i;
        ASSERT_NEAR(a.weight[da], b.weight[db], 1e-4f) << "point " << i;
    }
    EXPECT_GT(checked, 400);
}

// Operands in an order that follows space (a random walk, as a molecule's atoms or a sculpt's
// strokes come): the cells keep their stretches of the whole tape as Runs, a fraction of the
// instructions they stand for, every Run and jump inside its tape, and the values unchanged,
// scalar and batch, with bounds culling's guards inside the Runs and outside them (the operands
// are exact distances, so that culling keeps the values too).
TEST(Pruning, CellsKeepStretchesOfTheWholeTapeAsRuns) {
    Rng rng(5);
    std::vector<NodePtr> c{node::plane({0, 1, 0}, 0.1f)};
    Vec3 at(0, 0.5f, 0);
    for (int i = 0; i < 1500; ++i) {
        at = at + rng.direction() * 0.12f;
        at.y = std::clamp(at.y, 0.2f, 1.0f);
        // Every seventh a group of three, some of which a cell drops, so that its guard's jump
        // is renumbered.
        NodePtr leaf = node::sphere(0.1f);
        if (i % 7 == 0)
            leaf = node::unite({node::sphere(0.08f),
                                node::translate(node::box(Vec3(0.06f)), rng.inCube(0.3f)),
                                node::translate(node::sphere(0.05f), rng.inCube(0.3f))});
        c.push_back(node::translate(leaf, at));
    }
    const NodePtr root = node::unite(c);
    const Tape whole = compileTape(root, {.pruning = false});
    const Tape pruned = compileTape(root);
    ASSERT_NE(pruned.pruned(), nullptr);
    const PrunedTapes& p = *pruned.pruned();
    size_t stood = 0, runs = 0;
    for (size_t t = 0; t < p.spans.size() / 2; ++t) {
        if (static_cast<int32_t>(t) == p.outsideTape) continue;
        const uint32_t first = p.spans[2 * t], count = p.spans[2 * t + 1];
        for (uint32_t i = first; i < first + count; ++i) {
            const Instr& in = p.instrs[i];
            if (in.op == Op::Run) {
                ASSERT_LT(in.k, in.jump);
                ASSERT_LE(in.jump, whole.size());
                stood += in.jump - in.k;
                ++runs;
            } else {
                if (in.op == Op::CullIfFar) ASSERT_LE(in.jump, count) << "tape " << t;
                ++stood;
            }
        }
    }
    EXPECT_GT(runs, 0u);
    EXPECT_LT(3 * p.instrs.size(), stood);
    const Bounds3 box = p.box;
    std::vector<float> x, y, z;
    for (int i = 0; i < 4000; ++i) {
        Vec3 q = rng.inBox(box.lo, box.hi);
        if (i % 3) q = q + rng.direction() * (0.01f - whole.eval(q)) * 0.5f;
        ASSERT_NEAR(whole.eval(q), pruned.eval(q), 1e-5f * (std::fabs(whole.eval(q)) + 1));
        x.push_back(q.x), y.push_back(q.y), z.push_back(q.z);
    }
    std::vector<float> out(x.size());
    BatchScratch scratch;
    pruned.evalBatch(x.data(), y.data(), z.data(), out.data(), static_cast<int>(x.size()), scratch);
    for (size_t i = 0; i < x.size(); ++i)
        ASSERT_EQ(out[i], pruned.eval({x[i], y[i], z[i]})) << "point " << i;
}

TEST(Pruning, SmallOrUnprunableTapesKeepTheWholeTape) {
    EXPECT_EQ(compileTape(node::sphere(1)).pruned(), nullptr);
    EXPECT_EQ(compileTape(testing::everyKindTree()).pruned(), nullptr);
    // Many operands, all overlapping: no cell can drop any.
    std::vector<NodePtr> same;
    for (int i = 0; i < 30; ++i) same.push_back(node::sphere(1.0f + 0.001f * i));
    EXPECT_EQ(compileTape(node::unite(same)).pruned(), nullptr);
    // A few big blended strokes: bounds culling skips the far ones after one guard each, which is
    // all the cells would save; with many strokes the guards add up and the cells pay.
    auto strokes = [](int count) {
        Rng rng(3);
        const float spread = 0.5f * std::sqrt(static_cast<float>(count));
        std::vector<NodePtr> all;
        for (int s = 0; s < count; ++s) {
            Vec3 p = rng.inBox({-spread, 0.2f, -spread}, {spread, 0.6f, spread});
            NodePtr stroke;
            for (int i = 0; i < 16; ++i) {
                const Vec3 q = p + rng.direction() * 0.08f;
                NodePtr c = node::capsule(p, q, 0.035f);
                stroke = stroke ? node::smoothUnion(stroke, c, 0.06f) : c;
                p = q;
            }
            all.push_back(stroke);
        }
        return node::unite(all);
    };
    EXPECT_EQ(compileTape(strokes(4)).pruned(), nullptr);
    EXPECT_NE(compileTape(strokes(256)).pruned(), nullptr);
}

}  // namespace
}  // namespace sdft
