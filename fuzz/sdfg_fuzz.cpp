// Fuzz target: the .sdfg reader. The payload checksum is recomputed over the input before reading
// (mutations would otherwise stop at it), so the header and payload checks behind it are reached;
// a grid that loads is sampled and its surface blocks walked.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "fuzz_input.h"
#include "sdftrace/core/error.h"
#include "sdftrace/io/sdfg_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace sdft;
    fuzz::limitMemoryForFuzzing();
    constexpr size_t kHeader = 64, kChecksumAt = 56;
    std::vector<uint8_t> bytes(data, data + size);
    if (size >= kHeader) {
        const uint64_t sum = fnv1a64(bytes.data() + kHeader, size - kHeader);
        std::memcpy(bytes.data() + kChecksumAt, &sum, sizeof sum);
    }
    const std::string path = fuzz::writeScratchFile(bytes.data(), bytes.size(), ".sdfg");
    try {
        const Grid g = loadSdfg(path);
        const float v = g.view().interpolate(g.shape().bounds().center());
        if (std::isnan(v)) __builtin_trap();
        (void)g.memoryBytes();
    } catch (const InputError&) {
    }
    return 0;
}
