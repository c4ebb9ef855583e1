// The LBVH (Karras 2012): a well-formed tree (every triangle in one leaf, boxes holding their
// children, depth within the stack), its traversal equal bit for bit to testing every triangle with
// the same test, and agreeing with Embree's first hits (MeshBvh) on real meshes, for rays from
// outside, from inside, along the axes and starting behind their origin.
#include "sdftrace/bake/lbvh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/bake/test_meshes.h"
#include "sdftrace/exec/thread_arena.h"
#include "sdftrace/io/mesh_io.h"

namespace sdft {
namespace {

TriangleMesh load(const std::string& name) {
    return loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + name);
}

// Rays of every kind around the mesh's box: from outside towards points inside the box, from
// inside in random directions, along the axes (zero direction components), and a few starting
// just behind their origin (tnear < 0, as the RTSDF bake casts them).
struct TestRay {
    Ray ray;
    float tnear;
};
std::vector<TestRay> testRays(const TriangleMesh& mesh, int count, uint32_t seed) {
    const Bounds3 b = mesh.bounds();
    const Vec3 c = b.center(), e = b.extent();
    const float r = length(e);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    auto inBox = [&] { return b.lo + Vec3(u(rng), u(rng), u(rng)) * e; };
    auto direction = [&] {
        const float z = 1 - 2 * u(rng), phi = 6.2831853f * u(rng);
        const float s = std::sqrt(std::fmax(0.0f, 1 - z * z));
        return Vec3(s * std::cos(phi), s * std::sin(phi), z);
    };
    std::vector<TestRay> out;
    for (int i = 0; i < count; ++i) {
        switch (i % 4) {
            case 0: {  // from outside, through the box
                const Vec3 o = c + direction() * r, target = inBox();
                out.push_back({{o, normalize(target - o)}, 0.0f});
                break;
            }
            case 1:  // from inside the box
                out.push_back({{inBox(), direction()}, 0.0f});
                break;
            case 2: {  // along an axis
                Vec3 d(0.0f);
                d[i / 4 % 3] = (i / 12) % 2 ? 1.0f : -1.0f;
                out.push_back({{inBox(), d}, 0.0f});
                break;
            }
            default:  // behind the origin too
                out.push_back({{inBox(), direction()}, -1e-3f * r});
        }
    }
    return out;
}

void expectWellFormed(const Lbvh& bvh, const TriangleMesh& mesh) {
    const LbvhView v = bvh.view();
    ASSERT_EQ(v.count, static_cast<int>(mesh.triangles.size()));
    std::vector<int> seenLeaf(v.count, 0), seenNode(std::max(0, v.count - 1), 0);
    std::vector<uint8_t> idSeen(v.count, 0);
    for (const LbvhTriangle& t : bvh.triangles()) {
        ASSERT_LT(t.id, idSeen.size());
        EXPECT_FALSE(idSeen[t.id]) << "triangle " << t.id << " twice";
        idSeen[t.id] = 1;
    }
    if (v.count < 2) return;
    seenNode[0] = 1;  // the root
    for (int i = 0; i < v.count - 1; ++i) {
        const LbvhNode& n = v.nodes[i];
        for (int32_t child : {n.left, n.right}) {
            Vec3 lo, hi;
            if (child < 0) {
                ASSERT_LT(~child, v.count);
                ++seenLeaf[~child];
                const LbvhTriangle& t = v.triangles[~child];
                lo = min(t.a, min(t.b, t.c));
                hi = max(t.a, max(t.b, t.c));
            } else {
                ASSERT_LT(child, v.count - 1);
                ++seenNode[child];
                lo = v.nodes[child].lo;
                hi = v.nodes[child].hi;
            }
            for (int a = 0; a < 3; ++a) {
                EXPECT_LE(n.lo[a], lo[a]) << "node " << i;
                EXPECT_GE(n.hi[a], hi[a]) << "node " << i;
            }
        }
    }
    for (int i = 0; i < v.count; ++i) EXPECT_EQ(seenLeaf[i], 1) << "leaf " << i;
    for (int i = 0; i < v.count - 1; ++i) EXPECT_EQ(seenNode[i], 1) << "node " << i;
    Bounds3 b;  // of the vertices the triangles use
    for (const auto& t : mesh.triangles)
        for (uint32_t i : t) b.include(mesh.positions[i]);
    for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(v.nodes[0].lo[a], b.lo[a]);
        EXPECT_EQ(v.nodes[0].hi[a], b.hi[a]);
    }
    EXPECT_LE(bvh.depth(), 64);
}

// Same triangle test, so the traversal must find the very same t; the triangle may differ only on
// a tie (a ray through a shared edge).
void expectTraversalIsBruteForce(const Lbvh& bvh, const TriangleMesh& mesh, int rays, int minHits) {
    int hits = 0;
    for (const TestRay& tr : testRays(mesh, rays, 7)) {
        const LbvhHit a = lbvhFirstHit(bvh.view(), tr.ray, tr.tnear);
        const LbvhHit b = bruteForceFirstHit(bvh.view(), tr.ray, tr.tnear);
        ASSERT_EQ(a.t, b.t) << "ray from " << tr.ray.origin.x << " " << tr.ray.origin.y << " "
                            << tr.ray.origin.z;
        if (a.triangle == b.triangle) {
            EXPECT_EQ(a.front, b.front);
            EXPECT_EQ(a.u, b.u);
            EXPECT_EQ(a.v, b.v);
        }
        hits += a.t != kInfinity;
    }
    EXPECT_GE(hits, minHits);  // the rays do reach the mesh
}

TEST(Lbvh, IsWellFormedAndTraversesLikeBruteForceOnRealMeshes) {
    for (const char* name : {"bunny_npm.obj", "suzanne.obj", "teapot.obj"}) {
        SCOPED_TRACE(name);
        const TriangleMesh mesh = load(name);
        const Lbvh bvh(mesh);
        expectWellFormed(bvh, mesh);
        expectTraversalIsBruteForce(bvh, mesh, 2000, 500);
    }
}

TEST(Lbvh, HandlesTinyAndDegenerateInputs) {
    // One triangle, two, and a soup whose centroids all coincide (equal Morton codes: the index
    // below them keeps the keys unique).
    TriangleMesh one;
    one.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    one.triangles = {{0, 1, 2}};
    TriangleMesh same;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (int t = 0; t < 300; ++t) {
        const Vec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
        const uint32_t base = static_cast<uint32_t>(same.positions.size());
        same.positions.insert(same.positions.end(), {a, b, Vec3(0.0f) - a - b});
        same.triangles.push_back({base, base + 1, base + 2});
    }
    TriangleMesh two = testing::boxMesh(Vec3(1.0f));
    two.triangles.resize(2);
    for (const TriangleMesh* mesh : {&one, &two, &same}) {
        const Lbvh bvh(*mesh);
        expectWellFormed(bvh, *mesh);
        expectTraversalIsBruteForce(bvh, *mesh, 400, 40);  // a lone triangle is a small target
    }
    const Lbvh empty(TriangleMesh{});
    EXPECT_EQ(lbvhFirstHit(empty.view(), {{0, 0, 0}, {0, 0, 1}}).t, kInfinity);
}

TEST(Lbvh, TheBuildDoesNotDependOnTheThreadCount) {
    const TriangleMesh mesh = testing::icosphere(5);
    std::unique_ptr<Lbvh> one, two;
    ThreadArena(1).execute([&] { one = std::make_unique<Lbvh>(mesh, 1); });
    ThreadArena(2).execute([&] { two = std::make_unique<Lbvh>(mesh, 2); });
    ASSERT_EQ(one->nodes().size(), two->nodes().size());
    for (size_t i = 0; i < one->nodes().size(); ++i) {
        const LbvhNode &a = one->nodes()[i], &b = two->nodes()[i];
        ASSERT_EQ(a.left, b.left);
        ASSERT_EQ(a.right, b.right);
        for (int axis = 0; axis < 3; ++axis) {
            ASSERT_EQ(a.lo[axis], b.lo[axis]);
            ASSERT_EQ(a.hi[axis], b.hi[axis]);
        }
    }
}

// Two triangle tests (Möller-Trumbore here, Embree's own there) see the same surface: the same
// hit or miss and t within float rounding, except on rays through an edge or grazing a face.
TEST(Lbvh, AgreesWithEmbreesFirstHits) {
    for (const char* name : {"stanford-bunny.obj", "elephant-with-holes.obj", "teapot.obj"}) {
        SCOPED_TRACE(name);
        const TriangleMesh mesh = load(name);
        const Lbvh lbvh(mesh);
        const MeshBvh embree(mesh);
        const float scale = length(mesh.bounds().extent());
        int rays = 0, differ = 0, hits = 0;
        for (const TestRay& tr : testRays(mesh, 4000, 11)) {
            const LbvhHit a = lbvhFirstHit(lbvh.view(), tr.ray, tr.tnear);
            const MeshBvh::Hit b = embree.firstHit(tr.ray, tr.tnear);
            ++rays;
            hits += a.t != kInfinity;
            const bool same =
                (a.t == kInfinity) == (b.t == kInfinity) &&
                (a.t == kInfinity || (std::fabs(a.t - b.t) <= 1e-5f * scale && a.front == b.front));
            differ += !same;
        }
        EXPECT_GT(hits, rays / 4);
        EXPECT_LE(differ, rays / 1000) << differ << " of " << rays << " rays differ";
    }
}

// A tree deeper than the traversal stack (a comb: each spine node's far child a pair of leaves,
// every box the same) is answered as testing every triangle is: the ray whose stack would overflow
// falls back to that test instead of dropping subtrees. Shallower combs traverse normally.
TEST(Lbvh, ATreeDeeperThanTheStackStillFindsTheFirstHit) {
    for (int depth : {20, kLbvhStack + 16, 3 * kLbvhStack}) {
        const int count = 2 * depth + 1;
        std::vector<LbvhTriangle> triangles(count);
        std::mt19937 rng(static_cast<uint32_t>(depth));
        std::vector<int> order(count);
        for (int i = 0; i < count; ++i) order[i] = i;
        std::shuffle(order.begin(), order.end(), rng);
        for (int i = 0; i < count; ++i) {  // planes across the z axis at shuffled heights
            const float z = 1.0f + 0.01f * static_cast<float>(order[i]);
            triangles[i] = {{-1, -1, z}, {2, -1, z}, {-1, 2, z}, static_cast<uint32_t>(i)};
        }
        const LbvhNode box{{-1, -1, 0}, 0, {2, 2, 3}, 0};
        std::vector<LbvhNode> nodes(2 * depth, box);
        for (int i = 0; i < depth; ++i) {
            LbvhNode& spine = nodes[i];
            spine.left = i + 1 < depth ? i + 1 : ~(2 * depth);
            spine.right = depth + i;  // the pair, pushed first and left on the stack
            nodes[depth + i].left = ~(2 * i);
            nodes[depth + i].right = ~(2 * i + 1);
        }
        const LbvhView view{nodes.data(), triangles.data(), count};
        for (const Ray& r : {Ray{{0.1f, 0.2f, 0}, {0, 0, 1}}, Ray{{0.3f, 0.1f, 5}, {0, 0, -1}},
                             Ray{{5, 0.5f, 1.5f}, {-1, 0, 0}}}) {
            const LbvhHit a = lbvhFirstHit(view, r), b = bruteForceFirstHit(view, r);
            EXPECT_EQ(a.t, b.t) << depth;
            EXPECT_EQ(a.triangle, b.triangle) << depth;
        }
    }
}

}  // namespace
}  // namespace sdft
