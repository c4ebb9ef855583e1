#include "sdftrace/io/mesh_readers.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace sdft {

std::string lowerExtension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

MeshReader ownMeshReader(const std::string& path) {
    const std::string ext = lowerExtension(path);
    if (ext == ".ply") return readPly;
    if (ext == ".stl") return readStl;
    if (ext == ".off") return readOff;
    if (ext == ".obj") return readObj;
    return nullptr;
}

}  // namespace sdft
