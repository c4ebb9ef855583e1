#include <cstring>
#include <nlohmann/json.hpp>
#include <string_view>

#include "sdftrace/core/error.h"
#include "sdftrace/io/mapped_file.h"
#include "sdftrace/io/mesh_readers.h"

namespace sdft {

void precheckForAssimp(const std::string& path) {
    const std::string ext = lowerExtension(path);
    if (ext != ".glb" && ext != ".gltf") return;
    const MappedFile file(path);
    const char* d = file.data();
    const size_t n = file.size();
    auto fail = [&](const std::string& what) { throw InputError(path + ": " + what); };
    if (ext == ".gltf") {
        if (!nlohmann::json::accept(std::string_view(d, n)))
            fail("glTF: not valid JSON (a damaged file?)");
        return;
    }
    uint32_t header[3] = {0, 0, 0};
    if (n < 20) fail("GLB: " + std::to_string(n) + " bytes, shorter than a GLB header");
    std::memcpy(header, d, sizeof header);
    if (std::memcmp(d, "glTF", 4) != 0 || header[1] != 2)
        fail("GLB: not a glTF 2.0 binary (no 'glTF' version 2 header)");
    if (header[2] != n)
        fail("GLB: its header says " + std::to_string(header[2]) + " bytes, the file has " +
             std::to_string(n) + " (is it cut short?)");
    size_t at = 12;
    for (int chunk = 0; at < n; ++chunk) {
        uint32_t c[2];
        if (n - at < 8) fail("GLB: a chunk header runs past the end of the file");
        std::memcpy(c, d + at, sizeof c);
        if (c[0] > n - at - 8)
            fail("GLB: chunk " + std::to_string(chunk) + " of " + std::to_string(c[0]) +
                 " bytes runs past the end of the file");
        if (chunk == 0 &&
            (c[1] != 0x4E4F534Au || !nlohmann::json::accept(std::string_view(d + at + 8, c[0]))))
            fail("GLB: its first chunk is not valid JSON");
        at += 8 + static_cast<size_t>(c[0]);
    }
}

}  // namespace sdft
