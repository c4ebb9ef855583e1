#include "sdftrace/exec/simd.h"

#include <cstdlib>
#include <cstring>

#include "sdftrace/core/macros.h"

namespace sdft {

namespace detail {
namespace {
int initialLevel() {
#if SDFT_HAVE_AVX2_DISPATCH
    if (!__builtin_cpu_supports("avx2")) return 0;
    const char* env = std::getenv("SDFT_SIMD");
    if (env && (std::strcmp(env, "sse2") == 0 || std::strcmp(env, "baseline") == 0)) return 0;
    return 1;
#else
    return 0;
#endif
}
}  // namespace

// Decided during static initialization, before any dispatched function can run.
int g_useAvx2 = initialLevel();
}  // namespace detail

bool cpuHasAvx2() {
#if SDFT_HAVE_AVX2_DISPATCH
    return __builtin_cpu_supports("avx2");
#else
    return false;
#endif
}

SimdLevel simdLevel() { return useAvx2() ? SimdLevel::Avx2 : SimdLevel::Baseline; }

SimdLevel setSimdLevel(SimdLevel level) {
    const int avx2 = level == SimdLevel::Avx2 && cpuHasAvx2();
    __atomic_store_n(&detail::g_useAvx2, avx2, __ATOMIC_RELAXED);
    return simdLevel();
}

const char* simdLevelName(SimdLevel level) { return level == SimdLevel::Avx2 ? "avx2" : "sse2"; }

}  // namespace sdft
