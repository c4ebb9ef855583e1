// Arrays in and out of the point-query CLI (docs/file-formats.md, "Point arrays"): NumPy's .npy
// (format versions 1-3; float, integer and bool data, either byte order, C or Fortran order),
// .npz (a zip of .npy files, as numpy.savez writes it: stored, not compressed) and CSV (one row
// per line, numbers separated by commas or spaces, '#' comments, an optional header line).
// Readers check every field against the file's size: a damaged file is one InputError naming it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace sdft {

// An N x `cols` table of numbers as read: values row by row in double, and whether the file held
// 32-bit floats (answers are then written in float32 too).
struct PointTable {
    std::vector<double> values;
    size_t rows = 0, cols = 0;
    bool single = false;
};
// A .npy file or a CSV file (any other extension) of N rows of `cols` numbers; `what` names the
// argument in errors ("points").
PointTable readPointTable(const std::string& path, size_t cols);
PointTable parsePointTable(std::string_view bytes, const std::string& path, size_t cols);

// One output array: little-endian values of `kind` 'f' (float32 / float64 by itemsize), 'i'
// (int64) or 'b' (bool), rows x cols (cols 0: a vector).
struct NamedArray {
    std::string name;
    char kind = 'f';
    int itemsize = 4;
    size_t rows = 0, cols = 0;
    std::vector<uint8_t> bytes;
};
// The .npy file of an array (format version 1.0, or 2.0 for headers over 64 KiB).
std::string npyBytes(const NamedArray& a);
// Writes the arrays atomically by the extension: .npz (every array, named), .npy (exactly one),
// .csv (their columns side by side, a header naming them).
void writeArrays(const std::string& path, const std::vector<NamedArray>& arrays);

}  // namespace sdft
