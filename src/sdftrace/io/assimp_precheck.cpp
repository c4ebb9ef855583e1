#include <assimp/BaseImporter.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cstring>
#include <nlohmann/json.hpp>
#include <set>
#include <string_view>
#include <vector>

#include "sdftrace/core/error.h"
#include "sdftrace/io/mapped_file.h"
#include "sdftrace/io/mesh_readers.h"

namespace sdft {

namespace {

// assimp picks the importers whose extension ends the file's name; with none, or with several
// that all decline the content by its signature, it tries every importer on the bytes (and some
// read damaged ones out of bounds). So: an importer must claim the extension, and where several
// do, one of them must recognise the content.
void refuseGuessing(const std::string& path) {
    std::string name = path;
    std::transform(name.begin(), name.end(), name.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    Assimp::Importer importer;
    std::vector<Assimp::BaseImporter*> claiming;
    for (size_t i = 0; i < importer.GetImporterCount(); ++i) {
        Assimp::BaseImporter* imp = importer.GetImporter(i);
        std::set<std::string> extensions;
        if (imp) imp->GetExtensionList(extensions);
        for (const std::string& e : extensions) {
            const std::string dotted = "." + e;
            if (name.size() > dotted.size() &&
                name.compare(name.size() - dotted.size(), dotted.size(), dotted) == 0) {
                claiming.push_back(imp);
                break;
            }
        }
    }
    const std::string ext = lowerExtension(path);
    if (claiming.empty())
        throw InputError(path + ": unknown mesh format '" + ext +
                         "' (accepted: .obj, .ply, .stl, .off, .gltf, .glb and the other "
                         "extensions assimp reads, such as .dae, .fbx, .3ds, .x)");
    if (claiming.size() == 1) return;
    for (Assimp::BaseImporter* imp : claiming)
        if (imp->CanRead(path, importer.GetIOHandler(), true)) return;
    throw InputError(path + ": not a readable " + ext +
                     " file: no importer of the extension recognises its content (a damaged "
                     "file?)");
}

}  // namespace

void precheckForAssimp(const std::string& path) {
    const std::string ext = lowerExtension(path);
    if (ext != ".glb" && ext != ".gltf") return refuseGuessing(path);
    const MappedFile file(path);
    const char* d = file.data();
    const size_t n = file.size();
    auto fail = [&](const std::string& what) { throw InputError(path + ": " + what); };
    if (ext == ".gltf") {
        if (!nlohmann::json::accept(std::string_view(d, n)))
            fail("glTF: not valid JSON (a damaged file?)");
        return refuseGuessing(path);
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
    refuseGuessing(path);
}

}  // namespace sdft
