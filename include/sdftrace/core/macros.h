// Portability and invariant macros shared by every module.
#pragma once

#include <cstdio>
#include <cstdlib>

// Marks a function a GPU kernel could call later: header-visible, no throw, no allocation.
// Empty on the CPU (pbrt-v4's PBRT_CPU_GPU, NanoVDB's __hostdev__).
#if defined(__CUDACC__)
#define SDFT_HOST_DEVICE __host__ __device__
#else
#define SDFT_HOST_DEVICE
#endif

// Run-time SIMD dispatch (issue 15; exec/simd.h chooses): a hot CPU function is compiled twice,
// SDFT_TARGET_AVX2 for AVX2 and SDFT_TARGET_BASELINE for the x86-64 baseline (SSE2), both
// `flatten` so that every callee below them is inlined and built for the same target. FMA is not
// enabled: both versions round alike and return the same values. Without x86-64 GCC/Clang (CUDA,
// other CPUs) both are plain functions.
#if defined(__x86_64__) && !defined(__CUDACC__) && (defined(__GNUC__) || defined(__clang__))
#define SDFT_HAVE_AVX2_DISPATCH 1
#define SDFT_TARGET_AVX2 __attribute__((target("avx2"), flatten))
#define SDFT_TARGET_BASELINE __attribute__((flatten))
#else
#define SDFT_HAVE_AVX2_DISPATCH 0
#define SDFT_TARGET_AVX2
#define SDFT_TARGET_BASELINE
#endif

// A small function on the scalar tape evaluator's hot path, inlined on the CPU whatever GCC's
// heuristics make of the caller's size: they inlined tape_ops::pointOp into evalTapeAt in one
// build and called it in the next (7 % more instructions in a glass render). Device code keeps
// nvcc's own choice.
#if !defined(__CUDACC__) && (defined(__GNUC__) || defined(__clang__))
#define SDFT_HOT_INLINE __attribute__((always_inline)) inline
#else
#define SDFT_HOT_INLINE inline
#endif

// Fatal invariant check: prints file, line and the failed condition, then aborts.
// For programmer errors only; bad user input throws sdft::InputError instead.
#define SDFT_CHECK(cond)                                                                      \
    do {                                                                                      \
        if (!(cond)) {                                                                        \
            std::fprintf(stderr, "%s:%d: invariant failed: %s\n", __FILE__, __LINE__, #cond); \
            std::abort();                                                                     \
        }                                                                                     \
    } while (0)
