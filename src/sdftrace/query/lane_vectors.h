// Eight floats (and their comparison masks) as GCC's vector extension, for the query's lane
// tests: one AVX register where the calling function is compiled for AVX2, two SSE registers
// otherwise (exec/simd.h chooses at run time). Every function passing these vectors is inlined
// into its SDFT_TARGET_AVX2 or SDFT_TARGET_BASELINE caller: no call crosses the ABI boundary.
// Internal to src/sdftrace/query.
#pragma once

#pragma GCC diagnostic ignored "-Wpsabi"

namespace sdft::lane_vectors {

typedef float Floats __attribute__((vector_size(32)));
typedef int Ints __attribute__((vector_size(32)));

__attribute__((always_inline)) inline Floats load(const float* x) {
    Floats v;
    __builtin_memcpy(&v, x, sizeof v);
    return v;
}
__attribute__((always_inline)) inline Floats vmin(Floats a, Floats b) { return a < b ? a : b; }
__attribute__((always_inline)) inline Floats vmax(Floats a, Floats b) { return a > b ? a : b; }

// The squared gaps between eight boxes (lo[a], hi[a]: coordinate a of each of the eight) and the
// box [qlo, qhi] (a point where they are equal), 0 where they overlap; +inf for an empty box
// (lo = +inf, hi = -inf) against a finite query.
__attribute__((always_inline)) inline Floats gapSquared(const Floats lo[3], const Floats hi[3],
                                                        const Floats qlo[3], const Floats qhi[3]) {
    const Floats zero = {};
    Floats g[3];
    for (int a = 0; a < 3; ++a) g[a] = vmax(vmax(lo[a] - qhi[a], qlo[a] - hi[a]), zero);
    return g[0] * g[0] + g[1] * g[1] + g[2] * g[2];  // (no 0 + first: -0 keeps it an add)
}

// Bit l set where lane l of a comparison mask is: movmskps (extracting each lane and ORing them
// took a fifth of the point searches' time).
template <bool kAvx2>
__attribute__((always_inline)) inline unsigned laneBits(Ints m) {
    if constexpr (kAvx2) {
        return static_cast<unsigned>(__builtin_ia32_movmskps256(reinterpret_cast<Floats>(m)));
    } else {
        typedef int Ints4 __attribute__((vector_size(16)));
        typedef float Floats4 __attribute__((vector_size(16)));
        const Ints4 lo = __builtin_shufflevector(m, m, 0, 1, 2, 3);
        const Ints4 hi = __builtin_shufflevector(m, m, 4, 5, 6, 7);
        return static_cast<unsigned>(__builtin_ia32_movmskps(reinterpret_cast<Floats4>(lo))) |
               static_cast<unsigned>(__builtin_ia32_movmskps(reinterpret_cast<Floats4>(hi))) << 4;
    }
}

}  // namespace sdft::lane_vectors
