// Fuzz target: the .vdb importer (OpenVDB's reader, then sdftrace's conversion to a sparse grid).
#include <cmath>
#include <cstdint>

#include "fuzz_input.h"
#include "sdftrace/core/error.h"
#include "sdftrace/io/vdb_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace sdft;
    fuzz::limitMemoryForFuzzing();
    const std::string path = fuzz::writeScratchFile(data, size, ".vdb");
    try {
        const Grid g = loadVdb(path);
        const float v = g.view().interpolate(g.shape().bounds().center());
        if (std::isnan(v)) __builtin_trap();
    } catch (const InputError&) {
    }
    return 0;
}
