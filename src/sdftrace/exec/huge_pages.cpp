#include "sdftrace/exec/huge_pages.h"

#include <sys/mman.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>

namespace sdft {

namespace {

// madvise over the `align`-aligned interior of [data, data + bytes).
[[maybe_unused]] void adviseInterior(void* data, size_t bytes, uintptr_t align, int advice) {
    const uintptr_t begin = (reinterpret_cast<uintptr_t>(data) + align - 1) & ~(align - 1);
    const uintptr_t end = (reinterpret_cast<uintptr_t>(data) + bytes) & ~(align - 1);
    if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, advice);
}

}  // namespace

void adviseHugePages(void* data, size_t bytes) {
#ifdef MADV_HUGEPAGE
    adviseInterior(data, bytes, uintptr_t{2} << 20, MADV_HUGEPAGE);
#else
    (void)data;
    (void)bytes;
#endif
}

void touchPages(void* data, size_t bytes) {
    constexpr size_t kPage = 4096, kStep = size_t{2} << 20, kSmall = size_t{16} << 20;
    if (!data || bytes < kSmall) return;
    char* base = static_cast<char*>(data);
    tbb::parallel_for(size_t(0), (bytes + kStep - 1) / kStep, [&](size_t s) {
        const size_t end = std::min(bytes, (s + 1) * kStep);
        for (size_t at = s * kStep; at < end; at += kPage) base[at] = 0;
    });
}

void releasePages(void* data, size_t bytes) {
#ifdef MADV_DONTNEED
    adviseInterior(data, bytes, 4096, MADV_DONTNEED);
#else
    (void)data;
    (void)bytes;
#endif
}

}  // namespace sdft
