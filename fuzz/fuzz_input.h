// Helpers shared by the fuzz targets (fuzz/*_fuzz.cpp): reading fields off the fuzzer's bytes, and
// handing bytes to readers that take a path.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

#include "sdftrace/core/memory_budget.h"

namespace sdft::fuzz {

// Consumes the input from the front; past the end every read returns zeros.
class Input {
  public:
    Input(const uint8_t* data, size_t size) : m_data(data), m_size(size) {}
    template <class T>
    T take() {
        T v{};
        const size_t n = m_pos + sizeof(T) <= m_size ? sizeof(T) : m_size - m_pos;
        std::memcpy(&v, m_data + m_pos, n);
        m_pos += n;
        return v;
    }
    size_t left() const { return m_size - m_pos; }

  private:
    const uint8_t* m_data;
    size_t m_size, m_pos = 0;
};

// Fuzz inputs are at most a few kilobytes; a budget of 8 MiB makes a structure that asks for
// more (a grid of 10^9 blocks from a 4 KB file) a quick InputError rather than a long allocation or
// loop. What the budget refuses is tested by the budget tests; the targets look for crashes.
inline void limitMemoryForFuzzing() {
    static const bool once = (setMemoryBudgetBytes(8.0 * 1024 * 1024), true);
    (void)once;
}

// A file of this process's own (in TMPDIR, or /tmp), one per extension, that each input
// overwrites.
inline std::string writeScratchFile(const uint8_t* data, size_t size, const char* extension) {
    const char* dir = std::getenv("TMPDIR");
    const std::string path = std::string(dir && *dir ? dir : "/tmp") + "/sdftrace-fuzz-" +
                             std::to_string(getpid()) + extension;
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) std::abort();
    if (size && std::fwrite(data, 1, size, f) != size) std::abort();
    std::fclose(f);
    return path;
}

}  // namespace sdft::fuzz
