#include "sdftrace/query/lane_bvh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "sdftrace/io/mesh_io.h"
#include "sdftrace/query/triangle_closest.h"

namespace sdft {
namespace {

Vec3d widen(Vec3 v) { return {v.x, v.y, v.z}; }

// The least distance over every triangle, in double.
double bruteNearest(const TriangleMesh& m, Vec3 p) {
    double best = INFINITY;
    for (const auto& f : m.triangles)
        best = std::min(best, norm(widen(p) - closestOnTriangle(widen(p), widen(m.positions[f[0]]),
                                                                widen(m.positions[f[1]]),
                                                                widen(m.positions[f[2]]))
                                                  .point));
    return best;
}

// Over the tree of Morton groups the nearest triangle is the brute-force one (up to float
// rounding), near the surface, inside, far away and at a corner's tie; a radius short of it finds
// nothing, one at it finds it. A mesh of one triangle (a group of one, repeated) and the
// elephant's 4463 (a short last group) alike.
TEST(LaneBvh, NearestEqualsBruteForce) {
    TriangleMesh one;
    one.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
    one.triangles = {{0, 1, 2}};
    const TriangleMesh elephant =
        loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/elephant-with-holes.obj");
    for (const TriangleMesh* m : std::initializer_list<const TriangleMesh*>{&one, &elephant}) {
        const TriangleLanes lanes(*m);
        const LaneBvh bvh(lanes);
        const Bounds3 box = m->bounds();
        const float size = maxComponent(box.extent());
        std::mt19937 rng(3);
        std::uniform_real_distribution<float> u(0, 1);
        for (int k = 0; k < 400; ++k) {
            // A quarter of the points far away (100 sizes), the rest in the box grown by half.
            const float spread = k % 4 == 0 ? 100.0f : 0.5f;
            const Vec3 lo = box.lo - Vec3(spread * size), hi = box.hi + Vec3(spread * size);
            const Vec3 p = lo + (hi - lo) * Vec3(u(rng), u(rng), u(rng));
            const double best = bruteNearest(*m, p);
            const double tol = 1e-5 * (size + length(p));
            float d2 = 0;
            const uint32_t id = bvh.closest(p, INFINITY, d2);
            ASSERT_LT(id, m->triangles.size());
            EXPECT_NEAR(std::sqrt(d2), best, tol) << k;
            const auto& f = m->triangles[id];
            EXPECT_NEAR(norm(widen(p) - closestOnTriangle(widen(p), widen(m->positions[f[0]]),
                                                          widen(m->positions[f[1]]),
                                                          widen(m->positions[f[2]]))
                                            .point),
                        best, tol)
                << k;
            float none = 0;
            if (best > 10 * tol)
                EXPECT_EQ(bvh.closest(p, static_cast<float>(0.999 * best - tol), none), UINT32_MAX);
            EXPECT_NE(bvh.closest(p, static_cast<float>(best + tol), none), UINT32_MAX);
        }
    }
}

// near() finds exactly the groups whose boxes come within reach of a box (brute force over the
// groups' boxes), and says so when they are more than the limit.
TEST(LaneBvh, NearFindsTheGroupsWithinReach) {
    const TriangleMesh m = loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/suzanne.obj");
    const TriangleLanes lanes(m);
    const LaneBvh bvh(lanes);
    const Bounds3 box = m.bounds();
    const float size = maxComponent(box.extent());
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(0, 1);
    int some = 0;
    for (int k = 0; k < 200; ++k) {
        const Vec3 lo =
            box.lo - Vec3(0.2f * size) + box.extent() * 1.4f * Vec3(u(rng), u(rng), u(rng));
        const Vec3 hi = lo + Vec3(0.05f * size * u(rng));
        const float reach = 0.1f * size * u(rng);
        std::vector<uint32_t> brute;
        for (uint32_t g = 0; g < lanes.groups().size(); ++g) {
            const LaneGroup& group = lanes.groups()[g];
            Vec3 glo(INFINITY), ghi(-INFINITY);
            for (int l = 0; l < kLanes; ++l) {
                glo = min(glo, Vec3(group.f[kLox][l], group.f[kLoy][l], group.f[kLoz][l]));
                ghi = max(ghi, Vec3(group.f[kHix][l], group.f[kHiy][l], group.f[kHiz][l]));
            }
            const Vec3 gap = max(max(glo - hi, lo - ghi), Vec3(0.0f));
            if (dot(gap, gap) <= reach * reach) brute.push_back(g);
        }
        std::vector<uint32_t> found;
        ASSERT_TRUE(bvh.near(lo, hi, reach, found, SIZE_MAX));
        std::sort(found.begin(), found.end());
        ASSERT_EQ(found, brute) << k;
        if (brute.size() > 2) {
            std::vector<uint32_t> cut;
            EXPECT_FALSE(bvh.near(lo, hi, reach, cut, brute.size() - 1)) << k;
            ++some;
        }
    }
    EXPECT_GT(some, 20);
}

}  // namespace
}  // namespace sdft
