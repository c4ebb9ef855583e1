#include "sdftrace/bake/winding_number.h"

#include <gtest/gtest.h>

#include "sdftrace/field/test_util.h"
#include "sdftrace/io/mesh_io.h"

namespace sdft {
namespace {

TriangleMesh load(const std::string& name) {
    return loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + name);
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

}  // namespace
}  // namespace sdft
