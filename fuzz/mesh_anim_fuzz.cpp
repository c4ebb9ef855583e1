// Fuzz target: animated meshes as `render`/`bake` read a scene's moving mesh (AnimatedMesh::load,
// mesh_animation.h: assimp with its scene validated, then sdftrace's joints, morph targets and
// clips). The input is written as .gltf (or .glb where it starts with the GLB magic), loaded,
// and its first four clips posed at their start, middle and end: each pose is a finite mesh or an
// InputError.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>

#include "fuzz_input.h"
#include "sdftrace/core/error.h"
#include "sdftrace/io/mesh_animation.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace sdft;
    fuzz::limitMemoryForFuzzing();
    const bool glb = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
    const std::string path = fuzz::writeScratchFile(data, size, glb ? ".glb" : ".gltf");
    try {
        const AnimatedMesh mesh = AnimatedMesh::load(path);
        const int clips = static_cast<int>(mesh.clips().size());
        for (int c = 0; c < clips && c < 4; ++c)
            for (double at : {0.0, 0.5, 1.0}) {
                const double seconds = at * mesh.clips()[static_cast<size_t>(c)].duration;
                try {
                    const TriangleMesh posed = mesh.pose(c, seconds);
                    for (const Vec3& p : posed.positions)
                        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                            __builtin_trap();
                } catch (const InputError&) {
                }
            }
    } catch (const InputError&) {
    }
    return 0;
}
