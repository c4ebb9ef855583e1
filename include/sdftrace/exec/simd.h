// Run-time choice of the SIMD level for the functions built twice (core/macros.h,
// SDFT_TARGET_AVX2): the grid DDA and its normals, and the tape's batch evaluator. The release
// build targets any x86-64; the AVX2 versions run where the CPU has AVX2, unless the environment
// variable SDFT_SIMD=sse2 (or a call to setSimdLevel) asks for the baseline.
#pragma once

namespace sdft {

enum class SimdLevel { Baseline, Avx2 };

// The level in use: the best the CPU supports, lowered by SDFT_SIMD=sse2 on first use.
SimdLevel simdLevel();
// Whether this CPU (and build) can run the AVX2 versions.
bool cpuHasAvx2();
// Sets the level (tests, benchmarks); a level the CPU lacks falls back to the baseline. Returns
// the level now in use.
SimdLevel setSimdLevel(SimdLevel level);
// "avx2" or "sse2".
const char* simdLevelName(SimdLevel level);

namespace detail {
// 1 when the AVX2 versions run; read on every dispatch (one relaxed load).
extern int g_useAvx2;
}  // namespace detail

// The dispatch itself, in the header so that it inlines into the caller.
inline bool useAvx2() { return __atomic_load_n(&detail::g_useAvx2, __ATOMIC_RELAXED) != 0; }

}  // namespace sdft
