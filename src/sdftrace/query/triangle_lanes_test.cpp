#include "sdftrace/query/triangle_lanes.h"

#include <gtest/gtest.h>

#include <numeric>
#include <random>

#include "sdftrace/exec/simd.h"
#include "sdftrace/query/triangle_closest.h"

namespace sdft {
namespace {

Vec3d widen(Vec3 v) { return {v.x, v.y, v.z}; }

double exactDistance(const TriangleMesh& m, uint32_t t, Vec3 p) {
    const auto& f = m.triangles[t];
    const Vec3d q = widen(p);
    return norm(q - closestOnTriangle(q, widen(m.positions[f[0]]), widen(m.positions[f[1]]),
                                      widen(m.positions[f[2]]))
                        .point);
}

// Random triangles, a quarter of them degenerate (a repeated corner, collinear corners, one
// point): the lane test's least distance and its triangle equal the double-precision minimum
// over the same triangles within float rounding of the coordinates, for any number of triangles
// (a short last group), over all groups and over a list of some of them.
TEST(TriangleLanes, NearestEqualsTheExactMinimum) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1, 1);
    TriangleMesh all;
    for (int t = 0; t < 203; ++t) {
        const Vec3 a(u(rng), u(rng), u(rng));
        Vec3 b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
        if (t % 4 == 1) c = b;                   // a repeated corner
        if (t % 4 == 2) c = a + (b - a) * 0.3f;  // collinear
        if (t % 8 == 3) b = c = a;               // a point
        const auto base = static_cast<uint32_t>(all.positions.size());
        all.positions.insert(all.positions.end(), {a, b, c});
        all.triangles.push_back({base, base + 1, base + 2});
    }
    for (size_t count : {size_t{1}, size_t{5}, size_t{8}, size_t{203}}) {
        TriangleMesh m = all;
        m.triangles.resize(count);
        const TriangleLanes lanes(m);
        const std::vector<LaneGroup>& groups = lanes.groups();
        EXPECT_EQ(groups.size(), (count + 7) / 8);
        // Every triangle in the group groupOf() names, once.
        std::vector<int> seen(count);
        for (const LaneGroup& g : groups)
            for (int l = 0; l < kLanes; ++l) {
                ASSERT_LT(g.id[l], count);
                if (&g - groups.data() == lanes.groupOf(g.id[l])) seen[g.id[l]] += 1;
            }
        for (size_t t = 0; t < count; ++t) EXPECT_GE(seen[t], 1) << t;
        // Every other group, by list.
        std::vector<uint32_t> some;
        for (uint32_t g = 0; g < groups.size(); g += 2) some.push_back(g);
        for (int k = 0; k < 300; ++k) {
            const Vec3 p(2 * u(rng), 2 * u(rng), 2 * u(rng));
            double best = INFINITY, bestSome = INFINITY;
            for (uint32_t t = 0; t < count; ++t) {
                best = std::min(best, exactDistance(m, t, p));
                if (lanes.groupOf(t) % 2 == 0)
                    bestSome = std::min(bestSome, exactDistance(m, t, p));
            }
            uint32_t id = UINT32_MAX;
            const float d2 = nearestInGroups(groups.data(), groups.size(), p, INFINITY, id);
            ASSERT_LT(id, count);
            EXPECT_NEAR(std::sqrt(d2), best, 1e-5);
            EXPECT_NEAR(exactDistance(m, id, p), best, 1e-5);  // the winner is a nearest one
            uint32_t listed = UINT32_MAX;
            const float s2 =
                nearestInGroupList(groups.data(), some.data(), some.size(), p, INFINITY, listed);
            EXPECT_NEAR(std::sqrt(s2), bestSome, 1e-5);
            EXPECT_EQ(lanes.groupOf(listed) % 2, 0u);
            // A bound short of every box skips them all; one at the answer keeps the answer.
            double nearestBox = INFINITY;
            for (uint32_t t = 0; t < count; ++t) {
                const auto& f = m.triangles[t];
                const Vec3 a = m.positions[f[0]], b = m.positions[f[1]], c = m.positions[f[2]];
                const Vec3 gap = max(max(min(a, min(b, c)) - p, p - max(a, max(b, c))), Vec3(0.0f));
                nearestBox = std::min(nearestBox, static_cast<double>(length(gap)));
            }
            uint32_t none = UINT32_MAX;
            if (nearestBox > 0.01) {
                const auto below = static_cast<float>(0.9 * nearestBox);
                EXPECT_EQ(nearestInGroups(groups.data(), groups.size(), p, below * below, none),
                          INFINITY);
                EXPECT_EQ(none, UINT32_MAX);
            }
            const float bound = static_cast<float>(best * (1 + 1e-5) + 1e-6);
            EXPECT_NEAR(
                std::sqrt(nearestInGroups(groups.data(), groups.size(), p, bound * bound, none)),
                best, 1e-5);
        }
    }
}

// groupsWithinBounds lists, for each of 1-16 points, exactly the named groups whose box lies
// within its bound, in the order named; bounds of 0 (a point in a box only) and infinity too, on
// both SIMD levels.
TEST(TriangleLanes, GroupsWithinBoundsAreThoseWhoseBoxesReach) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<Bounds3> boxes(40);
    for (Bounds3& b : boxes) {
        const Vec3 a(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
        b.include(a);
        b.include(a + (c - a) * 0.3f);
    }
    std::vector<uint32_t> which(boxes.size());
    std::iota(which.begin(), which.end(), 0u);
    const SimdLevel before = simdLevel();
    for (SimdLevel level : {SimdLevel::Baseline, SimdLevel::Avx2}) {
        setSimdLevel(level);
        for (int round = 0; round < 50; ++round) {
            std::shuffle(which.begin(), which.end(), rng);
            const size_t count = 1 + rng() % which.size(), n = 1 + rng() % 16;
            Vec3 p[16];
            float bound2[16];
            for (size_t i = 0; i < n; ++i) {
                p[i] = Vec3(1.5f * u(rng), 1.5f * u(rng), 1.5f * u(rng));
                const float r = 0.5f * (u(rng) + 1);
                bound2[i] = i % 7 == 3 ? 0.0f : i % 7 == 5 ? INFINITY : r * r;
            }
            std::vector<uint32_t> out(n * count);
            uint32_t outCount[16];
            groupsWithinBounds(boxes.data(), which.data(), count, p, bound2, n, out.data(),
                               outCount);
            for (size_t i = 0; i < n; ++i) {
                std::vector<uint32_t> expected;
                for (size_t g = 0; g < count; ++g) {
                    const Bounds3& b = boxes[which[g]];
                    const Vec3 gap = max(max(b.lo - p[i], p[i] - b.hi), Vec3(0.0f));
                    if (dot(gap, gap) <= bound2[i]) expected.push_back(which[g]);
                }
                ASSERT_EQ(std::vector<uint32_t>(out.begin() + i * count,
                                                out.begin() + i * count + outCount[i]),
                          expected)
                    << "point " << i << " of " << n;
            }
        }
    }
    setSimdLevel(before);
}

}  // namespace
}  // namespace sdft
