#include "sdftrace/io/npy_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include "sdftrace/core/error.h"

namespace sdft {
namespace {

template <class T>
NamedArray arrayOf(const std::vector<T>& v, size_t cols, char kind) {
    NamedArray a;
    a.name = "a";
    a.kind = kind;
    a.itemsize = sizeof(T);
    a.rows = v.size() / cols;
    a.cols = cols;
    a.bytes.resize(v.size() * sizeof(T));
    std::memcpy(a.bytes.data(), v.data(), a.bytes.size());
    return a;
}

// What npyBytes writes, parsePointTable reads back: float32 stays float32, the rest is float64.
TEST(NpyIo, WrittenArraysReadBack) {
    const std::vector<float> f = {1.5f, -2, 3, 4, 5, 6.25f};
    PointTable t = parsePointTable(npyBytes(arrayOf(f, 3, 'f')), "f.npy", 3);
    EXPECT_TRUE(t.single);
    EXPECT_EQ(t.rows, 2u);
    EXPECT_EQ(t.values, std::vector<double>(f.begin(), f.end()));
    const std::vector<int64_t> i = {1, -2, 3};
    t = parsePointTable(npyBytes(arrayOf(i, 3, 'i')), "i.npy", 3);
    EXPECT_FALSE(t.single);
    EXPECT_EQ(t.values, (std::vector<double>{1, -2, 3}));
    const std::string bytes = npyBytes(arrayOf(f, 3, 'f'));
    EXPECT_EQ((bytes.size() - f.size() * 4) % 64, 0u);  // the data starts 64-byte aligned
}

// Fortran order, big-endian data and a version 2 header, as numpy may write them.
TEST(NpyIo, FortranOrderBigEndianAndVersionTwo) {
    std::string dict = "{'descr': '>f8', 'fortran_order': True, 'shape': (2, 3), }";
    dict.append(128 - 12 - dict.size() - 1, ' ');
    dict += '\n';
    std::string file = std::string("\x93NUMPY\x02\x00", 8);
    const uint32_t len = static_cast<uint32_t>(dict.size());
    file.append(reinterpret_cast<const char*>(&len), 4);
    file += dict;
    for (double v : {1.0, 4.0, 2.0, 5.0, 3.0, 6.0}) {  // column by column
        char b[8];
        std::memcpy(b, &v, 8);
        std::reverse(b, b + 8);
        file.append(b, 8);
    }
    const PointTable t = parsePointTable(file, "f.npy", 3);
    EXPECT_EQ(t.values, (std::vector<double>{1, 2, 3, 4, 5, 6}));
}

TEST(NpyIo, CsvWithHeaderCommentsAndSeparators) {
    const PointTable t = parsePointTable("x, y, z\n# note\n1,2,3\n4 5 6\r\n7;8;+9e0\n", "p.csv", 3);
    EXPECT_EQ(t.rows, 3u);
    EXPECT_EQ(t.values, (std::vector<double>{1, 2, 3, 4, 5, 6, 7, 8, 9}));
    EXPECT_EQ(parsePointTable("", "e.csv", 3).rows, 0u);
}

TEST(NpyIo, DamagedFilesAreOneErrorNamingTheFile) {
    const std::string good = npyBytes(arrayOf(std::vector<float>{1, 2, 3}, 3, 'f'));
    for (const std::string& bad :
         {good.substr(0, good.size() - 1), good.substr(0, 9), good + "x",
          std::string("\x93NUMPY\x09\x00\x10\x00", 10) + std::string(16, ' ')}) {
        try {
            parsePointTable(bad, "bad.npy", 3);
            ADD_FAILURE() << "accepted";
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()).rfind("bad.npy", 0), 0u) << e.what();
        }
    }
    std::string wrongShape = good;
    wrongShape.replace(wrongShape.find("(1, 3)"), 6, "(3, 1)");
    EXPECT_THROW(parsePointTable(wrongShape, "s.npy", 3), InputError);
    std::string huge = good;
    huge.replace(huge.find("(1, 3)"), 6, "(99999999999999999, 3)");
    EXPECT_THROW(parsePointTable(huge, "h.npy", 3), InputError);
    EXPECT_THROW(parsePointTable("1,2\n", "s.csv", 3), InputError);
    EXPECT_THROW(parsePointTable("1,2,3,4\n", "s.csv", 3), InputError);
    EXPECT_THROW(parsePointTable("1,2,3\n1,inf,3\n", "s.csv", 3), InputError);
}

}  // namespace
}  // namespace sdft
