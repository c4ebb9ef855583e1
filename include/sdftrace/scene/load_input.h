// What `render`, `view` and the Python module take as their input: a scene file (described, then
// its assets loaded and baked), a mesh (baked exactly at the default resolution) or a grid file
// (.sdfg, .vdb), each framed by an automatic camera and lit by default lights; "" is the
// built-in demo scene.
#pragma once
#include <string>

#include "sdftrace/scene/prepare_scene.h"
#include "sdftrace/scene/scene.h"

namespace sdft {

struct LoadedInput {
    Scene scene;
    // What was done to a mesh or grid input, for one line on stderr ("" for scene files).
    std::string note;
};

// Throws InputError naming the file. `meshBaker`: how a scene file's meshes bake
// (prepare_scene.h).
LoadedInput loadSceneInput(const std::string& input, bool progress = false,
                           const MeshBaker& meshBaker = {});

}  // namespace sdft
