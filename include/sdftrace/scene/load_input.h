// What `render`, `view` and the Python module take as their input: a scene file (described, then
// its assets loaded and baked), a mesh (baked exactly at the default resolution) or a grid file
// (.sdfg, .vdb), each framed by an automatic camera and lit by default lights; "" is the
// built-in demo scene.
#pragma once
#include <string>

#include "sdftrace/render/render_settings.h"
#include "sdftrace/scene/prepare_scene.h"
#include "sdftrace/scene/scene.h"

namespace sdft {

struct LoadedInput {
    Scene scene;
    // What was done to a mesh or grid input, for one line on stderr ("" for scene files).
    std::string note;
};

// Throws InputError naming the file. `meshBaker`: how a scene file's meshes bake
// (prepare_scene.h). `gapLattice` false: a mesh's or grid file's narrow band enters the scene
// without its gap lattice (sceneGrid), for a render that never reads it (below).
LoadedInput loadSceneInput(const std::string& input, bool progress = false,
                           const MeshBaker& meshBaker = {}, bool gapLattice = true);

// Whether a render with `settings` of a mesh or grid file (one grid, one plastic material) reads
// the grid's distance bound, which the gap lattice tightens beyond the band (decision 19): sphere
// tracing it, the path tracer, ambient occlusion, soft shadows and shadow maps. The DDA's primary
// rays and its hard and distributed shadow rays walk the blocks and never read it.
bool loneGridReadsDistances(const RenderSettings& settings);

}  // namespace sdft
