#include "sdftrace/bake/winding_number.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "sdftrace/bake/test_meshes.h"
#include "sdftrace/bake/winding_view.h"
#include "sdftrace/exec/thread_arena.h"
#include "sdftrace/field/test_util.h"
#include "sdftrace/io/mesh_io.h"

namespace sdft {
namespace {

TriangleMesh load(const std::string& name) {
    return loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + name);
}

// The tree's two halves build in parallel above 16k triangles into preassigned slots: the same
// tree, hence the same values to the bit, on any number of threads.
TEST(WindingNumber, ParallelBuildIsTheSequentialOne) {
    const TriangleMesh sphere = testing::icosphere(6);  // 81,920 triangles
    ASSERT_GT(sphere.triangles.size(), 65536u);
    std::unique_ptr<WindingNumber> one, four;
    ThreadArena(1).execute([&] { one = std::make_unique<WindingNumber>(sphere); });
    ThreadArena(4).execute([&] { four = std::make_unique<WindingNumber>(sphere); });
    for (int n = 0; n < 400; ++n) {
        const float u = static_cast<float>(n) / 400.0f;
        const Vec3 p(2.4f * u - 1.2f, std::sin(37.0f * u) * 1.1f, std::cos(23.0f * u) * 0.9f);
        EXPECT_EQ(one->fast(p), four->fast(p)) << p.x << " " << p.y << " " << p.z;
        EXPECT_EQ(one->fast(p, 1.5), four->fast(p, 1.5));
    }
    // And a correct tree: the hierarchy against the exact sum.
    for (int n = 0; n < 40; ++n) {
        const float u = static_cast<float>(n) / 40.0f;
        const Vec3 p(2.4f * u - 1.2f, std::sin(37.0f * u) * 1.1f, std::cos(23.0f * u) * 0.9f);
        EXPECT_NEAR(four->fast(p), four->exact(p), 0.03) << p.x << " " << p.y << " " << p.z;
    }
}

TEST(WindingNumber, IsOneInsideAndZeroOutsideAClosedMesh) {
    TriangleMesh bunny = load("bunny_npm.obj");
    WindingNumber w(bunny);
    Bounds3 b = bunny.bounds();
    Vec3 c = b.center();
    EXPECT_NEAR(w.exact(c + Vec3(0, -0.1f * b.extent().y, 0)), 1.0, 1e-6);  // in the body
    EXPECT_NEAR(w.exact(b.hi + b.extent()), 0.0, 1e-6);
}

// Barill et al.'s hierarchy against the exact sum, on a closed and an open mesh (the test:
// on elephant-with-holes the sign agrees with a brute-force reference on a small grid).
TEST(WindingNumber, HierarchicalMatchesTheExactSumAndItsSign) {
    for (const char* name : {"bunny_npm.obj", "elephant-with-holes.obj"}) {
        TriangleMesh mesh = load(name);
        WindingNumber w(mesh);
        Bounds3 b = mesh.bounds().expanded(0.1f * maxComponent(mesh.bounds().extent()));
        const int n = 12;
        int signs = 0, inside = 0;
        double worst = 0;
        for (int k = 0; k <= n; ++k)
            for (int j = 0; j <= n; ++j)
                for (int i = 0; i <= n; ++i) {
                    Vec3 p = b.lo + b.extent() * Vec3(i, j, k) / static_cast<float>(n);
                    double e = w.exact(p), f = w.fast(p);
                    worst = std::max(worst, std::fabs(e - f));
                    if (std::fabs(e - 0.5) > 0.05) {
                        EXPECT_EQ(e > 0.5, f > 0.5)
                            << name << " at " << p.x << "," << p.y << "," << p.z;
                        ++signs;
                    }
                    inside += e > 0.5;
                }
        EXPECT_LT(worst, 0.03) << name;  // first-order dipoles at beta = 3 (measured 0.023)
        EXPECT_GT(signs, 2000) << name;
        EXPECT_GT(inside, 30) << name;
    }
}

// inside() first asks a coarse beta (1.5) and takes its answer when clear of 1/2 by 0.3; it must
// agree with fast() > 1/2 everywhere, also near the surface and around holes.
TEST(WindingNumber, TwoTierInsideAgreesWithTheFullEvaluation) {
    for (const char* name : {"bunny_npm.obj", "elephant-with-holes.obj", "suzanne.obj"}) {
        TriangleMesh mesh = load(name);
        WindingNumber w(mesh);
        Bounds3 b = mesh.bounds().expanded(0.05f * maxComponent(mesh.bounds().extent()));
        const int n = 40;
        int inside = 0;
        for (int k = 0; k <= n; ++k)
            for (int j = 0; j <= n; ++j)
                for (int i = 0; i <= n; ++i) {
                    Vec3 p = b.lo + b.extent() * Vec3(i, j, k) / static_cast<float>(n);
                    bool full = w.fast(p) > 0.5;
                    ASSERT_EQ(w.inside(p), full)
                        << name << " at " << p.x << "," << p.y << "," << p.z;
                    inside += full;
                }
        EXPECT_GT(inside, 500) << name;
    }
}

// A tree deeper than the traversal stack (a comb whose spine runs down the child popped first, so
// each level leaves its sibling on the stack) still gets every triangle's solid angle: a node whose
// children would not fit is summed exactly over its range of triangles.
TEST(WindingNumber, ATreeDeeperThanTheStackStillSumsEveryTriangle) {
    for (int depth : {30, kWindingStack + 20, 3 * kWindingStack}) {
        const int count = 2 * depth + 1;
        std::mt19937 rng(static_cast<uint32_t>(depth));
        std::uniform_real_distribution<float> u(-1.0f, 1.0f);
        std::vector<float> corners(9 * static_cast<size_t>(count));
        for (float& c : corners) c = u(rng);
        // Spine node i covers triangles [2i, count), its leaf pair [2i, 2i + 2); the last leaf
        // [2 depth, count). Radii so large that no node is far enough for its dipole.
        std::vector<WindingNode> nodes(2 * depth + 1);
        auto leaf = [](WindingNode& n, int first, int n_count) {
            n.radius = 1e30;
            n.first = first;
            n.count = n_count;
        };
        for (int i = 0; i < depth; ++i) {
            leaf(nodes[i], 2 * i, count - 2 * i);
            nodes[i].left = depth + i;
            nodes[i].right = i + 1 < depth ? i + 1 : 2 * depth;
            leaf(nodes[depth + i], 2 * i, 2);
        }
        leaf(nodes[2 * depth], 2 * depth, 1);
        const WindingView view{nodes.data(), static_cast<int>(nodes.size()), corners.data()};
        for (const Vec3 p : {Vec3(0, 0, 0), Vec3(0.3f, -0.2f, 0.5f), Vec3(3, 1, -2)}) {
            double exact = 0;
            for (int t = 0; t < count; ++t) exact += solidAngleFloat(p, corners.data() + 9 * t);
            exact /= 12.566370614359172;
            EXPECT_NEAR(windingNumberFast(view, p, 2.0), exact, 1e-5) << depth;
        }
    }
}

}  // namespace
}  // namespace sdft
