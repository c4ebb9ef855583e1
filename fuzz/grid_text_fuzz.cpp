// Fuzz target: the grid formats of other tools that `convert`, `render` and scenes read through
// loadGridFile: SDFGen's `.sdf` (text) and raw float32 with its `.raw.json` sidecar. The input's
// first byte picks the format; for raw, the next two bytes give the sidecar's length, then the
// sidecar, then the samples. A grid that loads is sampled at its centre.
#include <cmath>
#include <cstdint>
#include <string>

#include "fuzz_input.h"
#include "sdftrace/core/error.h"
#include "sdftrace/io/grid_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace sdft;
    fuzz::limitMemoryForFuzzing();
    if (size < 1) return 0;
    const bool raw = data[0] & 1;
    ++data;
    --size;
    std::string path;
    if (raw) {
        size_t sidecar = size >= 2 ? (size_t{data[0]} | size_t{data[1]} << 8) : 0;
        data += std::min<size_t>(size, 2);
        size -= std::min<size_t>(size, 2);
        sidecar = std::min(sidecar, size);
        path = fuzz::writeScratchFile(data + sidecar, size - sidecar, ".raw");
        const std::string json = fuzz::writeScratchFile(data, sidecar, ".raw.json");
        (void)json;  // the raw file's path + ".json": the same name the reader looks for
    } else {
        path = fuzz::writeScratchFile(data, size, ".sdf");
    }
    try {
        const Grid g = loadGridFile(path);
        const float v = g.view().interpolate(g.shape().bounds().center());
        if (std::isnan(v)) __builtin_trap();
    } catch (const InputError&) {
    }
    return 0;
}
