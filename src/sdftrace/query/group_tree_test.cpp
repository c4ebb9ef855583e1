#include "sdftrace/query/group_tree.h"

#include <gtest/gtest.h>

#include <random>

#include "sdftrace/exec/simd.h"

namespace sdft {
namespace {

// near() returns exactly the groups whose boxes come within the reach of the query box, in
// increasing order, for any count of groups (one, a partial node, several levels), query boxes
// and points inside, beside and far from the boxes, reaches of 0 and infinity; false once more
// than `limit` reach; on both SIMD levels.
TEST(GroupTree, NearIsEveryBoxWithinReach) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1, 1);
    const SimdLevel before = simdLevel();
    for (size_t count :
         {size_t{1}, size_t{7}, size_t{8}, size_t{9}, size_t{64}, size_t{77}, size_t{600}}) {
        std::vector<Bounds3> boxes(count);
        for (Bounds3& b : boxes) {
            const Vec3 c(u(rng), u(rng), u(rng));
            b.include(c);
            b.include(c + Vec3(0.1f * (u(rng) + 1), 0.1f * (u(rng) + 1), 0.1f * (u(rng) + 1)));
        }
        const GroupTree tree(boxes);
        EXPECT_EQ(tree.levels().back().size(), 1u);
        for (SimdLevel level : {SimdLevel::Baseline, SimdLevel::Avx2}) {
            setSimdLevel(level);
            for (int k = 0; k < 200; ++k) {
                const Vec3 lo(1.5f * u(rng), 1.5f * u(rng), 1.5f * u(rng));
                const Vec3 hi = k % 3 == 0 ? lo : lo + Vec3(0.2f * (u(rng) + 1));
                const float reach = k % 11 == 0   ? 0.0f
                                    : k % 11 == 1 ? INFINITY
                                                  : 0.6f * (u(rng) + 1);
                std::vector<uint32_t> expected;
                for (uint32_t g = 0; g < count; ++g) {
                    const Vec3 gap = max(max(boxes[g].lo - hi, lo - boxes[g].hi), Vec3(0.0f));
                    if (dot(gap, gap) <= reach * reach) expected.push_back(g);
                }
                std::vector<uint32_t> got = {12345};  // appended to what is there
                ASSERT_TRUE(tree.near(lo, hi, reach, got, count));
                ASSERT_EQ(got.front(), 12345u);
                ASSERT_EQ(std::vector<uint32_t>(got.begin() + 1, got.end()), expected)
                    << count << " groups, query " << k;
                if (!expected.empty()) {
                    std::vector<uint32_t> cut;
                    EXPECT_FALSE(tree.near(lo, hi, reach, cut, expected.size() - 1));
                    EXPECT_TRUE(tree.near(lo, hi, reach, cut = {}, expected.size()));
                }
            }
        }
    }
    setSimdLevel(before);
}

}  // namespace
}  // namespace sdft
