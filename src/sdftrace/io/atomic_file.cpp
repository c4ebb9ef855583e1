#include "sdftrace/io/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <utility>

#include "sdftrace/core/error.h"

namespace sdft {

namespace fs = std::filesystem;

namespace {

// Temporary paths of live AtomicOutputs, for removeTemporaryOutputs (a signal handler may read
// them at any time: fixed storage, a slot is published by its flag after its path is written).
constexpr int kSlots = 64;
constexpr size_t kPathBytes = 4096;
char g_paths[kSlots][kPathBytes];
std::atomic<bool> g_used[kSlots];

int claimSlot(const std::string& path) {
    if (path.size() >= kPathBytes) return -1;
    for (int i = 0; i < kSlots; ++i) {
        bool expected = false;
        if (g_used[i].load() || !g_used[i].compare_exchange_strong(expected, true)) continue;
        // Claimed but not yet published: write the path, then mark it with a leading byte.
        g_paths[i][0] = '\0';
        std::memcpy(g_paths[i] + 1, path.c_str(), path.size() + 1);
        std::atomic_thread_fence(std::memory_order_release);
        g_paths[i][0] = '/';
        return i;
    }
    return -1;  // more than kSlots outputs at once: still removed by the destructor
}

void releaseSlot(int slot) {
    if (slot < 0) return;
    g_paths[slot][0] = '\0';
    g_used[slot].store(false);
}

}  // namespace

void removeTemporaryOutputs() noexcept {
    for (int i = 0; i < kSlots; ++i)
        if (g_used[i].load() && g_paths[i][0] == '/') ::unlink(g_paths[i] + 1);
}

std::string writeErrorReason(const std::string& path, int err) {
    std::string reason = std::strerror(err);
    std::error_code ec;
    fs::path dir = fs::path(path).parent_path();
    if (dir.empty()) dir = ".";
    switch (err) {
        case ENOSPC:
        case EDQUOT:
            return reason + ": the file system is full";
        case EFBIG:
            return reason + ": over the file-size limit (ulimit -f) or the file system's";
        case ENOENT:
            if (!fs::is_directory(dir, ec))
                return "the directory " + dir.string() + " no longer exists";
            return reason;
        case EROFS:
            return reason + ": the file system is read-only";
        default:
            return reason;
    }
}

AtomicOutput::AtomicOutput(std::string finalPath) : m_final(std::move(finalPath)) {
    m_temp = m_final + ".tmp." + std::to_string(::getpid());
    m_slot = claimSlot(m_temp);
}

AtomicOutput::~AtomicOutput() {
    if (m_file) std::fclose(m_file);
    if (!m_committed) std::remove(m_temp.c_str());
    releaseSlot(m_slot);
}

void AtomicOutput::fail(int err) const {
    throw InputError(m_final + ": cannot write the output file (" + writeErrorReason(m_final, err) +
                     "); nothing was written there");
}

void AtomicOutput::write(const void* data, size_t bytes) {
    if (!m_file) {
        m_file = std::fopen(m_temp.c_str(), "wb");
        if (!m_file) fail(errno);
    }
    if (bytes && std::fwrite(data, 1, bytes, m_file) != bytes) fail(errno ? errno : EIO);
}

void AtomicOutput::writeAt(uint64_t offset, const void* data, size_t bytes) {
    if (!m_file) fail(EBADF);
    if (::fseeko(m_file, static_cast<off_t>(offset), SEEK_SET) != 0) fail(errno);
    write(data, bytes);
    if (::fseeko(m_file, 0, SEEK_END) != 0) fail(errno);
}

void AtomicOutput::commit() {
    int fd = -1;
    if (m_file) {
        if (std::fflush(m_file) != 0) fail(errno);
        fd = ::fileno(m_file);
    } else {
        fd = ::open(m_temp.c_str(), O_RDONLY);
        if (fd < 0) fail(errno);
    }
    // On disk before the rename, so a crash never leaves a short file at the final path.
    const int syncError = ::fsync(fd) == 0 ? 0 : errno;
    if (m_file) {
        const int closeError = std::fclose(m_file) == 0 ? 0 : errno;
        m_file = nullptr;
        if (closeError) fail(closeError);
    } else {
        ::close(fd);
    }
    if (syncError && syncError != EINVAL) fail(syncError);
    if (std::rename(m_temp.c_str(), m_final.c_str()) != 0) fail(errno);
    m_committed = true;
}

SharedTemporary::SharedTemporary(std::string path)
    : m_path(std::move(path)), m_slot(claimSlot(m_path)) {}

SharedTemporary::~SharedTemporary() {
    if (!m_path.empty()) ::unlink(m_path.c_str());
    releaseSlot(m_slot);
}

void SharedTemporary::release() {
    m_path.clear();
    releaseSlot(m_slot);
    m_slot = -1;
}

void writeFileAtomically(const std::string& path, const void* data, size_t bytes) {
    AtomicOutput out(path);
    out.write(data, bytes);
    out.commit();
}

void checkWritablePath(const std::string& path, const std::string& what) {
    if (path.empty()) throw InputError(what + ": empty output path");
    fs::path p(path);
    std::error_code ec;
    if (fs::is_directory(p, ec)) {
        throw InputError(what + " " + path + ": is a directory; give a file name");
    }
    fs::path dir = p.parent_path();
    if (dir.empty()) dir = ".";
    if (!fs::is_directory(dir, ec)) {
        throw InputError(what + " " + path + ": directory " + dir.string() + " does not exist");
    }
    if (::access(dir.c_str(), W_OK) != 0) {
        throw InputError(what + " " + path + ": directory " + dir.string() + " is not writable");
    }
}

}  // namespace sdft
