// A whole file mapped read-only into memory (mmap, prefaulted): readers parse it in place instead
// of copying it into a buffer first.
#pragma once

#include <cstddef>
#include <string>

namespace sdft {

class MappedFile {
  public:
    // Throws InputError naming `path` when it cannot be opened or mapped.
    explicit MappedFile(const std::string& path);
    ~MappedFile();
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;

    const char* data() const { return m_data; }
    size_t size() const { return m_size; }

  private:
    const char* m_data = nullptr;
    size_t m_size = 0;
};

}  // namespace sdft
