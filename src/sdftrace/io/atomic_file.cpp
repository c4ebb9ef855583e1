#include "sdftrace/io/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "sdftrace/core/error.h"

namespace sdft {

namespace fs = std::filesystem;

AtomicOutput::AtomicOutput(std::string finalPath) : m_final(std::move(finalPath)) {
    m_temp = m_final + ".tmp." + std::to_string(::getpid());
}

AtomicOutput::~AtomicOutput() {
    if (!m_committed) std::remove(m_temp.c_str());
}

void AtomicOutput::commit() {
    if (std::rename(m_temp.c_str(), m_final.c_str()) != 0) {
        std::string why = std::strerror(errno);
        std::remove(m_temp.c_str());
        throw InputError(m_final + ": cannot write the output file (" + why + ")");
    }
    m_committed = true;
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
