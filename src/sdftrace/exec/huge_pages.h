// Large working arrays backed by transparent huge pages where the kernel offers them on request
// (THP "madvise" mode, Debian's default): first touches then fault once per 2 MiB instead of once
// per 4 KiB. On this project's VM the 4 KiB faults were a third of a narrow-band bake.
#pragma once

#include <cstddef>
#include <vector>

namespace sdft {

// Advises the kernel to back [data, data + bytes) with huge pages (the 2 MiB-aligned interior);
// a no-op where unsupported.
void adviseHugePages(void* data, size_t bytes);

// Gives the whole pages inside [data, data + bytes) back to the system (they read as zeros if
// touched again); a no-op where unsupported.
void releasePages(void* data, size_t bytes);

// Faults in the pages of freshly allocated [data, data + bytes) from every core (a zero byte
// written per page), so that the kernel clears them in parallel rather than in the one thread
// that fills the array next: on this project's VM that clearing was a third of loading a large
// grid. Small ranges are left alone.
void touchPages(void* data, size_t bytes);

// v = n copies of value, allocated first, advised and faulted in, then written (std::vector
// touches its memory when it fills it, so the advice must come between).
template <class T>
void assignHuge(std::vector<T>& v, size_t n, const T& value) {
    std::vector<T>().swap(v);
    v.reserve(n);
    adviseHugePages(v.data(), n * sizeof(T));
    touchPages(v.data(), n * sizeof(T));
    v.assign(n, value);
}

}  // namespace sdft
