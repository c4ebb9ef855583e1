// Fuzz target: mesh files as the CLI reads them. The input is written to a file with the format's
// extension and loaded by loadMesh (mesh_io.h), the function `sdftrace bake`, scenes and Python
// call: sdftrace's own readers for PLY, STL, OFF and OBJ, assimp (its scene validated) for
// glTF/GLB. Built once per format family (SDFT_FUZZ_MESH_EXT: ply, stl, off, obj, gltf; the gltf
// target writes an input that starts with the GLB magic as .glb). Every input loads a finite,
// non-empty mesh or fails with an InputError; nothing else may escape.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>

#include "fuzz_input.h"
#include "sdftrace/core/error.h"
#include "sdftrace/io/mesh_io.h"

#ifndef SDFT_FUZZ_MESH_EXT
#error "SDFT_FUZZ_MESH_EXT names the format family (ply, stl, off, obj, gltf)"
#endif

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace sdft;
    fuzz::limitMemoryForFuzzing();
    std::string ext = std::string(".") + SDFT_FUZZ_MESH_EXT;
    if (ext == ".gltf" && size >= 4 && std::memcmp(data, "glTF", 4) == 0) ext = ".glb";
    const std::string path = fuzz::writeScratchFile(data, size, ext.c_str());
    try {
        const TriangleMesh mesh = loadMesh(path);
        if (mesh.triangles.empty()) __builtin_trap();
        for (const auto& t : mesh.triangles)
            for (uint32_t v : t)
                if (v >= mesh.positions.size()) __builtin_trap();
        for (const Vec3& p : mesh.positions)
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) __builtin_trap();
    } catch (const InputError&) {
    }
    return 0;
}
