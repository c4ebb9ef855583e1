#include "sdftrace/query/triangle_lanes.h"

#include <gtest/gtest.h>

#include <numeric>
#include <random>

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
// (a short last group).
TEST(TriangleLanes, NearestEqualsTheExactMinimum) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1, 1);
    TriangleMesh m;
    for (int t = 0; t < 203; ++t) {
        const Vec3 a(u(rng), u(rng), u(rng));
        Vec3 b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
        if (t % 4 == 1) c = b;                   // a repeated corner
        if (t % 4 == 2) c = a + (b - a) * 0.3f;  // collinear
        if (t % 8 == 3) b = c = a;               // a point
        const auto base = static_cast<uint32_t>(m.positions.size());
        m.positions.insert(m.positions.end(), {a, b, c});
        m.triangles.push_back({base, base + 1, base + 2});
    }
    const TriangleLanes lanes(m);
    std::vector<LaneGroup> groups;
    for (size_t count : {size_t{1}, size_t{5}, size_t{8}, size_t{203}}) {
        std::vector<uint32_t> ids(count);
        std::iota(ids.begin(), ids.end(), 0u);
        lanes.gather(ids.data(), count, groups);
        EXPECT_EQ(groups.size(), (count + 7) / 8);
        for (int k = 0; k < 300; ++k) {
            const Vec3 p(2 * u(rng), 2 * u(rng), 2 * u(rng));
            double best = INFINITY;
            for (uint32_t t = 0; t < count; ++t) best = std::min(best, exactDistance(m, t, p));
            uint32_t id = UINT32_MAX;
            const float d2 = nearestInGroups(groups.data(), groups.size(), p, INFINITY, id);
            ASSERT_LT(id, count);
            EXPECT_NEAR(std::sqrt(d2), best, 1e-5);
            EXPECT_NEAR(exactDistance(m, id, p), best, 1e-5);  // the winner is a nearest one
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

}  // namespace
}  // namespace sdft
