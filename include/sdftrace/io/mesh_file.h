// Which files are meshes (loaded through assimp): .obj, .ply, .stl, .off, .gltf, .glb.
#pragma once

#include <algorithm>
#include <filesystem>
#include <string>

namespace sdft {

inline bool isMeshFile(const std::string& path) {
    std::string e = std::filesystem::path(path).extension().string();
    std::transform(e.begin(), e.end(), e.begin(), ::tolower);
    return e == ".obj" || e == ".ply" || e == ".stl" || e == ".off" || e == ".gltf" || e == ".glb";
}
// Files that may hold skinned or morph animation (a scene's "play"): glTF, Collada, FBX,
// DirectX .x.
inline bool isAnimatedMeshFile(const std::string& path) {
    std::string e = std::filesystem::path(path).extension().string();
    std::transform(e.begin(), e.end(), e.begin(), ::tolower);
    return e == ".gltf" || e == ".glb" || e == ".dae" || e == ".fbx" || e == ".x";
}

}  // namespace sdft
