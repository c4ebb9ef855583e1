// Output files that appear whole or not at all: written to a temporary name beside the target,
// flushed to disk, then renamed over it. A failure (an exception, a full disk, a directory that
// disappeared, a file-size limit) leaves no file behind and says what happened; so does SIGINT,
// SIGTERM or SIGHUP (removeTemporaryOutputs), and after SIGKILL the output path still holds
// either the old file or the whole new one (only a stray temporary can remain).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

namespace sdft {

class AtomicOutput {
  public:
    explicit AtomicOutput(std::string finalPath);
    ~AtomicOutput();  // closes and removes the temporary file unless commit() succeeded
    AtomicOutput(const AtomicOutput&) = delete;
    AtomicOutput& operator=(const AtomicOutput&) = delete;

    const std::string& finalPath() const { return m_final; }
    // For writers that open the file themselves (OpenEXR, OpenVDB): they write here.
    const std::string& tempPath() const { return m_temp; }
    // Checked writing: opens the temporary file on the first call; any failed write throws an
    // InputError that names the final path and the reason.
    void write(const void* data, size_t bytes);
    // Overwrites `bytes` already written at `offset` (a header whose fields are known only once
    // the rest is written), then goes on writing at the end.
    void writeAt(uint64_t offset, const void* data, size_t bytes);
    // Flushes and syncs what write() wrote (or checks the file a writer left at tempPath()),
    // then renames it over the final path; throws InputError with the reason on failure.
    void commit();
    // Throws the InputError for errno value `err` (open, write, close or rename of this file).
    [[noreturn]] void fail(int err) const;

  private:
    std::string m_final, m_temp;
    std::FILE* m_file = nullptr;
    int m_slot = -1;  // in the registry removeTemporaryOutputs walks
    bool m_committed = false;
};

// Another process's temporary output that this one writes into (the ranks of a distributed bake
// write parts of rank 0's file): removed by removeTemporaryOutputs while registered, so that a
// job whose writer was killed leaves no partial file, and by the destructor unless released.
class SharedTemporary {
  public:
    explicit SharedTemporary(std::string path);
    ~SharedTemporary();
    SharedTemporary(const SharedTemporary&) = delete;
    SharedTemporary& operator=(const SharedTemporary&) = delete;
    // The file was committed (renamed into place): leave it.
    void release();

  private:
    std::string m_path;
    int m_slot = -1;
};

// Writes `bytes` to `path` atomically (AtomicOutput).
void writeFileAtomically(const std::string& path, const void* data, size_t bytes);

// "No space left on device (the file system is full)", "the directory /x no longer exists", ...:
// the reason part of a write error for `path` and errno value `err`.
std::string writeErrorReason(const std::string& path, int err);

// Removes every temporary output file of the process; async-signal-safe (the CLI calls it from
// its SIGINT / SIGTERM / SIGHUP handler).
void removeTemporaryOutputs() noexcept;

// Throws InputError naming `what` (e.g. "--output") unless `path`'s directory exists and is
// writable and `path` is not a directory. Checked before long work starts.
void checkWritablePath(const std::string& path, const std::string& what);

}  // namespace sdft
