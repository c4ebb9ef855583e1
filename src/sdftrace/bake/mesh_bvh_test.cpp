#include "sdftrace/bake/mesh_bvh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "sdftrace/bake/test_meshes.h"
#include "sdftrace/bake/winding_number.h"

namespace sdft {
namespace {

using testing::boxMesh;

// Along a segment the winding number of a closed mesh changes by the crossings windingChange()
// counts, wherever it says it is sure; segments ending on a face or along one are not sure.
// Two boxes overlapping (winding 2 where they do) and sharing part of a face, whose coplanar
// triangles a segment crosses together, are counted both.
TEST(MeshBvh, WindingChangeCountsOrientedCrossings) {
    TriangleMesh mesh = boxMesh(Vec3(1.0f, 0.5f, 0.5f));
    const TriangleMesh second = boxMesh(Vec3(0.5f, 0.5f, 1.0f));  // shares the y = +-0.5 planes
    for (const auto& f : second.triangles) mesh.triangles.push_back({f[0] + 8, f[1] + 8, f[2] + 8});
    mesh.positions.insert(mesh.positions.end(), second.positions.begin(), second.positions.end());
    const MeshBvh bvh(mesh);
    const WindingNumber exact(mesh);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1.5f, 1.5f);
    int sure = 0, crossing = 0;
    for (int k = 0; k < 2000; ++k) {
        const Vec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
        int change = 0;
        if (!bvh.windingChange(a, b, change)) continue;
        ++sure;
        crossing += change != 0;
        ASSERT_EQ(change, std::lround(exact.exact(b)) - std::lround(exact.exact(a)));
    }
    EXPECT_GT(sure, 1900);
    EXPECT_GT(crossing, 300);
    int change = 0;
    EXPECT_FALSE(bvh.windingChange(Vec3(0.2f, 0.1f, -1.5f), Vec3(0.2f, 0.1f, -0.5f), change));
    EXPECT_FALSE(bvh.windingChange(Vec3(-1.5f, 0.5f, 0.1f), Vec3(1.5f, 0.5f, 0.1f), change));
    // Through the shared y = 0.5 face where both boxes have it: out of both at once.
    ASSERT_TRUE(bvh.windingChange(Vec3(0.1f, 0.2f, 0.1f), Vec3(0.1f, 0.9f, 0.2f), change));
    EXPECT_EQ(change, -2);
}

}  // namespace
}  // namespace sdft
