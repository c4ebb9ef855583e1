// One line of the exact separable Euclidean distance transform (Felzenszwalb and Huttenlocher
// 2012, §2.1: the lower envelope of the parabolas rooted at the line's finite values): shared by
// the grids' gap lattices (gap_lattice.cpp, float) and the bakers' feature transform
// (bake/separable_edt.cpp, double, with the minimizing index).
#pragma once

#include <limits>

namespace sdft {

// f[q] (a squared distance so far, +infinity for none) -> out[q] = min_r (q - r)^2 + f[r], and
// from[q] = the minimizing r where `from` is given (out[q] = +infinity and from[q] = -1 on a line
// without a finite value). v, z: scratch of n and n + 1 entries.
template <class T>
void lowerEnvelope(int n, const T* f, T* out, int* from, int* v, T* z) {
    constexpr T kInf = std::numeric_limits<T>::infinity();
    int k = -1;
    for (int q = 0; q < n; ++q) {
        if (f[q] == kInf) continue;
        if (k < 0) {
            k = 0, v[0] = q, z[0] = -kInf, z[1] = kInf;
            continue;
        }
        T s;
        while (true) {  // z[0] = -inf ends it
            const int r = v[k];
            s = ((f[q] + T(q) * T(q)) - (f[r] + T(r) * T(r))) / (T(2) * T(q - r));
            if (s > z[k]) break;
            --k;
        }
        ++k;
        v[k] = q, z[k] = s, z[k + 1] = kInf;
    }
    if (k < 0) {
        for (int q = 0; q < n; ++q) {
            out[q] = kInf;
            if (from) from[q] = -1;
        }
        return;
    }
    k = 0;
    for (int q = 0; q < n; ++q) {
        while (z[k + 1] < T(q)) ++k;
        const T d = T(q) - T(v[k]);
        out[q] = d * d + f[v[k]];
        if (from) from[q] = v[k];
    }
}

}  // namespace sdft
