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

void* operator new(std::size_t bytes) { return allocate(bytes); }
void* operator new[](std::size_t bytes) { return allocate(bytes); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
