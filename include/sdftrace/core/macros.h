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

// Fatal invariant check: prints file, line and the failed condition, then aborts.
// For programmer errors only; bad user input throws sdft::InputError instead.
#define SDFT_CHECK(cond)                                                                      \
    do {                                                                                      \
        if (!(cond)) {                                                                        \
            std::fprintf(stderr, "%s:%d: invariant failed: %s\n", __FILE__, __LINE__, #cond); \
            std::abort();                                                                     \
        }                                                                                     \
    } while (0)
