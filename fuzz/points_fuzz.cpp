// Fuzz target: the point tables `sdftrace query` reads (.npy and CSV, io/npy_io.h). The input's
// first byte picks the format (odd: .npy, even: CSV); a table that parses is written back as .npy
// and must read back equal.
#include <cstdint>
#include <cstring>
#include <string>

#include "fuzz_input.h"
#include "sdftrace/core/error.h"
#include "sdftrace/io/npy_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace sdft;
    fuzz::limitMemoryForFuzzing();
    if (size < 1) return 0;
    const bool npy = data[0] & 1;
    std::string bytes(reinterpret_cast<const char*>(data + 1), size - 1);
    if (npy && bytes.rfind("\x93NUMPY", 0) != 0) bytes = "\x93NUMPY" + bytes;
    try {
        const PointTable t = parsePointTable(bytes, npy ? "p.npy" : "p.csv", 3);
        NamedArray a;
        a.name = "p";
        a.kind = 'f';
        a.itemsize = 8;
        a.rows = t.rows;
        a.cols = 3;
        a.bytes.resize(t.values.size() * 8);
        if (!t.values.empty()) std::memcpy(a.bytes.data(), t.values.data(), a.bytes.size());
        const PointTable back = parsePointTable(npyBytes(a), "back.npy", 3);
        if (back.values != t.values || back.rows != t.rows) __builtin_trap();
    } catch (const InputError&) {
    }
    return 0;
}
