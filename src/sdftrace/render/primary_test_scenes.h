// The example scenes the per-pixel primary path is checked on (render/primary_pixel_test.cpp on
// the CPU, gpu/gpu_primary_test.cpp on a GPU): analytic scenes, CSG, smooth blends, displacement,
// repetition, textures, grids and baked meshes in the tape. Single-grid DDA scenes and the path
// tracer have primary paths of their own; every scene listed must be traceable per pixel.
#pragma once

#include <array>
#include <cmath>
#include <vector>

namespace sdft::testing {

inline constexpr std::array<const char*, 14> kPrimaryTestScenes = {
    "csg",        "blob",      "city", "demo",    "glass",    "glass_shapes", "jewel",
    "many_blend", "projected", "rock", "shadows", "textures", "thin",         "hybrid"};

// Whether pixel (x, y) of a w x h depth image is next to one whose hit state differs, or whose
// depth differs by more than 2%: an edge, where a rounding difference between devices may move
// the ray to the other side (the GPU tests compare off these).
inline bool nearDepthEdge(const std::vector<float>& depth, int w, int h, int x, int y) {
    const float d = depth[static_cast<size_t>(y) * w + x];
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            const int u = x + dx, v = y + dy;
            if (u < 0 || v < 0 || u >= w || v >= h) continue;
            const float e = depth[static_cast<size_t>(v) * w + u];
            if (std::isfinite(d) != std::isfinite(e)) return true;
            if (std::isfinite(d) && std::fabs(d - e) > 0.02f * d) return true;
        }
    }
    return false;
}

}  // namespace sdft::testing
