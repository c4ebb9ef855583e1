#include "sdftrace/io/mapped_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "sdftrace/core/error.h"
#include "test_files.h"

namespace sdft {
namespace {

using testing::tempPath;

// Released pages leave the process, not the file: reading them again gives the same bytes.
TEST(MappedFile, ReleasedPiecesReadTheSameAgain) {
    const std::string path = tempPath("mapped.bin");
    std::string bytes(3 << 16, '\0');
    for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<char>(i * 7 + i / 4096);
    std::ofstream(path, std::ios::binary) << bytes;
    for (MappedFile::Load load : {MappedFile::Load::Prefault, MappedFile::Load::Lazy}) {
        const MappedFile file(path, load);
        ASSERT_EQ(file.size(), bytes.size());
        file.release(100, 70000);  // whole pages within it only
        file.release(0, bytes.size());
        file.release(bytes.size() - 10, 1000);  // past the end: clipped
        EXPECT_EQ(std::string(file.data(), file.size()), bytes);
    }
    std::filesystem::remove(path);
    EXPECT_THROW(MappedFile(tempPath("missing.bin")), InputError);
}

}  // namespace
}  // namespace sdft
