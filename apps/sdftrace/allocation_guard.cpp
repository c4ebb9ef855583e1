// The allocation guard of the sdftrace executable (and of the fuzz targets): a single allocation
// larger than the memory budget (core/memory_budget.h, --max-memory) throws std::bad_alloc at once
// instead of asking the system for it. sdftrace's own arrays are checked with a clear message
// before they are made; this catches what third-party readers allocate from sizes stated in a
// file (a corrupt .vdb can ask OpenVDB for 2^58 bytes), which the readers then report as a bad
// file rather than the process being killed for memory later.
#include <cstdlib>
#include <new>

#include "sdftrace/core/memory_budget.h"

namespace {
void* allocate(std::size_t bytes) {
    if (static_cast<double>(bytes) > sdft::memoryBudgetBytes()) throw std::bad_alloc();
    if (void* p = std::malloc(bytes ? bytes : 1)) return p;
    throw std::bad_alloc();
}
}  // namespace

static void* allocateOrNull(std::size_t bytes) noexcept {
    try {
        return allocate(bytes);
    } catch (const std::bad_alloc&) {
        return nullptr;
    }
}

// Every form that pairs with free(): the plain, array and nothrow ones (std::stable_sort's
// temporary buffer uses nothrow new). The aligned forms stay the library's, new and delete alike.
void* operator new(std::size_t bytes) { return allocate(bytes); }
void* operator new[](std::size_t bytes) { return allocate(bytes); }
void* operator new(std::size_t bytes, const std::nothrow_t&) noexcept {
    return allocateOrNull(bytes);
}
void* operator new[](std::size_t bytes, const std::nothrow_t&) noexcept {
    return allocateOrNull(bytes);
}
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
