// The example scenes the per-pixel primary path is checked on (render/primary_pixel_test.cpp on
// the CPU, gpu/gpu_primary_test.cpp on a GPU): analytic scenes, CSG, smooth blends, displacement,
// repetition, textures, grids and baked meshes in the tape. Single-grid DDA scenes and the path
// tracer have primary paths of their own; every scene listed must be traceable per pixel.
#pragma once

#include <array>

namespace sdft::testing {

inline constexpr std::array<const char*, 14> kPrimaryTestScenes = {
    "csg",        "blob",      "city", "demo",    "glass",    "glass_shapes", "jewel",
    "many_blend", "projected", "rock", "shadows", "textures", "thin",         "hybrid"};

}  // namespace sdft::testing
