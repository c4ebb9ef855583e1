#include "sdftrace/io/atomic_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "sdftrace/core/error.h"
#include "test_files.h"

namespace sdft {
namespace {

using testing::tempPath;

TEST(AtomicOutput, AppearsWholeOnCommitAndNotAtAllOtherwise) {
    const std::string path = tempPath("a.bin");
    {
        AtomicOutput out(path);
        out.write("abc", 3);
        EXPECT_FALSE(std::filesystem::exists(path));
        EXPECT_TRUE(std::filesystem::exists(out.tempPath()));
    }
    EXPECT_FALSE(std::filesystem::exists(path)) << "no commit, no file";
    writeFileAtomically(path, "abcd", 4);
    EXPECT_EQ(std::filesystem::file_size(path), 4u);
    std::filesystem::remove(path);
}

// A header whose fields are known only at the end is written over its placeholder.
TEST(AtomicOutput, WriteAtOverwritesAndWritingGoesOnAtTheEnd) {
    const std::string path = tempPath("at.bin");
    {
        AtomicOutput out(path);
        out.write("0000abc", 7);
        out.writeAt(1, "XY", 2);
        out.write("de", 2);
        out.commit();
    }
    std::ifstream in(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(bytes, "0XY0abcde");
    std::filesystem::remove(path);
    AtomicOutput unopened(tempPath("none.bin"));
    EXPECT_THROW(unopened.writeAt(0, "x", 1), InputError);  // nothing written yet to overwrite
}

// What the CLI's SIGINT / SIGTERM handler calls: every live temporary file goes.
TEST(AtomicOutput, TemporaryFilesAreRemovedForASignal) {
    AtomicOutput a(tempPath("x.bin")), b(tempPath("y.bin"));
    a.write("1", 1);
    b.write("2", 1);
    removeTemporaryOutputs();
    EXPECT_FALSE(std::filesystem::exists(a.tempPath()));
    EXPECT_FALSE(std::filesystem::exists(b.tempPath()));
}

TEST(AtomicOutput, AVanishedDirectoryIsNamed) {
    const std::string dir = tempPath("gone");
    std::filesystem::create_directory(dir);
    AtomicOutput out(dir + "/f.bin");
    std::filesystem::remove_all(dir);
    try {
        out.write("abc", 3);
        out.commit();
        FAIL() << "wrote into a directory that does not exist";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("the directory " + dir + " no longer exists"),
                  std::string::npos)
            << e.what();
    }
}

}  // namespace
}  // namespace sdft
