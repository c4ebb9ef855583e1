// A whole file mapped read-only into memory (mmap): readers parse it in place instead of copying it
// into a buffer first. Prefaulted by default; a reader that walks a large file in pieces maps it
// lazily and releases each piece once read, so the file never counts whole in its memory.
#pragma once

#include <cstddef>
#include <string>

namespace sdft {

class MappedFile {
  public:
    enum class Load { Prefault, Lazy };
    // Throws InputError naming `path` when it cannot be opened or mapped.
    explicit MappedFile(const std::string& path, Load load = Load::Prefault);
    ~MappedFile();
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;

    const char* data() const { return m_data; }
    size_t size() const { return m_size; }
    // Drops the whole pages within [offset, offset + bytes) from the process's memory (the file
    // stays in the page cache; reading them again faults them back in).
    void release(size_t offset, size_t bytes) const;

  private:
    const char* m_data = nullptr;
    size_t m_size = 0;
};

}  // namespace sdft
