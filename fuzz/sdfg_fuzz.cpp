// Fuzz target: the .sdfg reader. The header's checksum is recomputed over the input before
// reading (mutations would otherwise stop at it): versions 1-2 over the payload, versions 3-5 over
// their section headers and chunk table, so the checks behind it and the zstd chunks are reached; a
// grid that loads is sampled, and what `info` reads of it (readSdfgSummary) agrees with it.
#include <algorithm>
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
    constexpr size_t kChunkCountAt = kHeader + 24;
    if (size >= kHeader) {
        uint32_t version = 0;
        std::memcpy(&version, bytes.data() + 4, sizeof version);
        // The section header: 32 bytes, and the table header of version 4 (8) or 5 (24).
        const size_t kSections = 32 + (version == 5 ? 24 : version == 4 ? 8 : 0);
        uint64_t sum = 0;
        if (version >= 3 && version <= 5 && size >= kHeader + kSections) {
            uint64_t chunks = 0;
            std::memcpy(&chunks, bytes.data() + kChunkCountAt, sizeof chunks);
            const size_t available = (size - kHeader - kSections) / sizeof(uint64_t);
            const size_t table = static_cast<size_t>(std::min<uint64_t>(chunks, available));
            sum = fnv1a64(bytes.data() + kHeader + kSections, table * sizeof(uint64_t),
                          fnv1a64(bytes.data() + kHeader, kSections));
        } else {
            sum = fnv1a64(bytes.data() + kHeader, size - kHeader);
        }
        std::memcpy(bytes.data() + kChecksumAt, &sum, sizeof sum);
    }
    const std::string path = fuzz::writeScratchFile(bytes.data(), bytes.size(), ".sdfg");
    bool described = false;
    SdfgSummary summary;
    try {
        summary = readSdfgSummary(path);  // what `info` reads: the header and tables
        described = true;
    } catch (const InputError&) {
    }
    try {
        const Grid g = loadSdfg(path);
        const float v = g.view().interpolate(g.shape().bounds().center());
        if (std::isnan(v)) __builtin_trap();
        // A file that loads is described, and as it loads: the same blocks, no more memory.
        size_t inside = 0, outside = 0, surface = 0;
        g.blockCounts(inside, outside, surface);
        if (!described || summary.blocks.surface != surface || summary.blocks.inside != inside ||
            summary.memoryBytes > g.memoryBytes())
            __builtin_trap();
    } catch (const InputError&) {
    }
    return 0;
}
