// The run-time SIMD level: the CPU's best unless lowered, never above what the CPU has.
#include "sdftrace/exec/simd.h"

#include <gtest/gtest.h>

#include <cstring>

namespace sdft {
namespace {

TEST(Simd, LevelFollowsRequestsWithinWhatTheCpuHas) {
    const SimdLevel was = simdLevel();
    EXPECT_EQ(setSimdLevel(SimdLevel::Baseline), SimdLevel::Baseline);
    EXPECT_FALSE(useAvx2());
    EXPECT_EQ(setSimdLevel(SimdLevel::Avx2), cpuHasAvx2() ? SimdLevel::Avx2 : SimdLevel::Baseline);
    EXPECT_EQ(useAvx2(), cpuHasAvx2());
    EXPECT_STREQ(simdLevelName(SimdLevel::Avx2), "avx2");
    EXPECT_STREQ(simdLevelName(SimdLevel::Baseline), "sse2");
    setSimdLevel(was);
    // The environment variable decides the level at start: SDFT_SIMD=sse2 gives the baseline.
    const char* env = std::getenv("SDFT_SIMD");
    if (env && std::strcmp(env, "sse2") == 0) {
        EXPECT_EQ(was, SimdLevel::Baseline);
    } else {
        EXPECT_EQ(was, cpuHasAvx2() ? SimdLevel::Avx2 : SimdLevel::Baseline);
    }
}

}  // namespace
}  // namespace sdft
