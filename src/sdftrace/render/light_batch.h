// A directional light's Lambert + Blinn-Phong term (direct_pixel::lightTerm) for a tile's hits at
// once, as the CPU renderer shades them: eight hits to an AVX2 register where it runs. The float
// operations are lightTerm's in its order (no FMA: core/macros.h), so every hit gets lightTerm's
// value bit for bit (light_batch_test.cpp); the device keeps lightTerm, a pixel to a thread.
#pragma once

#include "sdftrace/render/direct_pixel.h"

namespace sdft {

// radiance[h] += lightTerm(light, materials[h], p, normals[h], views[h], visible[h]) for every h
// in [0, n), for a directional light (whose term does not depend on the point p). shared: every
// hit has materials[0] (the others are not read).
void addDirectionalLight(const Light& light, const PixelMaterial* materials, bool shared,
                         const Vec3* normals, const Vec3* views, const float* visible, int n,
                         Vec3* radiance);

}  // namespace sdft
