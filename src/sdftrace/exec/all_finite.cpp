#include "sdftrace/exec/all_finite.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

namespace sdft {

namespace {
float nonFinite(const float* v, size_t begin, size_t end) {
    float sum = 0;
    for (size_t i = begin; i < end; ++i) sum += v[i] * 0.0f;
    return sum;
}
}  // namespace

bool allFinite(const float* values, size_t count) {
    constexpr size_t kGrain = size_t{1} << 16;
    if (count <= kGrain) return nonFinite(values, 0, count) == 0.0f;
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, count, kGrain), true,
        [&](const tbb::blocked_range<size_t>& r, bool ok) {
            return ok && nonFinite(values, r.begin(), r.end()) == 0.0f;
        },
        [](bool a, bool b) { return a && b; });
}

}  // namespace sdft
