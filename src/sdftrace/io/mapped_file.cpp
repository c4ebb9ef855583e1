#include "sdftrace/io/mapped_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "sdftrace/core/error.h"

namespace sdft {

MappedFile::MappedFile(const std::string& path, Load load) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        throw InputError(path + ": cannot open (" + std::strerror(errno) + "; does it exist?)");
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        ::close(fd);
        throw InputError(path + ": not a regular file");
    }
    m_size = static_cast<size_t>(st.st_size);
    if (m_size > 0) {
        const int populate = load == Load::Prefault ? MAP_POPULATE : 0;
        void* p = ::mmap(nullptr, m_size, PROT_READ, MAP_PRIVATE | populate, fd, 0);
        if (p == MAP_FAILED) {
            const int err = errno;
            ::close(fd);
            throw InputError(path + ": cannot map the file (" + std::strerror(err) + ")");
        }
        ::madvise(p, m_size, load == Load::Prefault ? MADV_SEQUENTIAL : MADV_WILLNEED);
        m_data = static_cast<const char*>(p);
    }
    ::close(fd);
}

void MappedFile::release(size_t offset, size_t bytes) const {
    static const size_t page = static_cast<size_t>(::sysconf(_SC_PAGESIZE));
    const size_t begin = (offset + page - 1) / page * page;
    const size_t end = std::min(offset + bytes, m_size) / page * page;
    if (m_data && begin < end)
        ::madvise(const_cast<char*>(m_data) + begin, end - begin, MADV_DONTNEED);
}

MappedFile::~MappedFile() {
    if (m_data) ::munmap(const_cast<char*>(m_data), m_size);
}

}  // namespace sdft
