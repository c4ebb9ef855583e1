// Output files that appear whole or not at all: write to a temporary name beside the target, then
// rename. A failure (or an exception) leaves no file behind.
#pragma once

#include <string>

namespace sdft {

class AtomicOutput {
  public:
    explicit AtomicOutput(std::string finalPath);
    ~AtomicOutput();  // removes the temporary file unless commit() succeeded
    AtomicOutput(const AtomicOutput&) = delete;
    AtomicOutput& operator=(const AtomicOutput&) = delete;

    const std::string& tempPath() const { return m_temp; }
    void commit();  // rename over the final path; throws InputError on failure

  private:
    std::string m_final, m_temp;
    bool m_committed = false;
};

// Throws InputError naming `what` (e.g. "--output") unless `path`'s directory exists and is
// writable and `path` is not a directory. Checked before long work starts.
void checkWritablePath(const std::string& path, const std::string& what);

}  // namespace sdft
