// A mesh file's polygon as triangles, for the readers of mesh_readers.h: triangles as they are,
// convex polygons as a fan, concave ones by ear clipping in their plane, the winding kept.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "sdftrace/math/vec.h"

namespace sdft {

// Ear clipping is quadratic in the corners: larger concave polygons (rare; a damaged file can
// hold one of any size) are fanned.
constexpr size_t kMaxEarClippedCorners = 64;

// Appends polygon `poly` (indices into `positions`) to `out`: a triangle as it is; a convex
// polygon as a fan from its first corner; a concave one of up to kMaxEarClippedCorners corners by
// ear clipping in the plane of its Newell normal (as assimp's aiProcess_Triangulate does), so a
// concave quad or an L-shaped n-gon gives no triangle outside it. A polygon with a corner not yet
// read (a PLY whose faces come first), no area, or no ear left is fanned. Fewer than three
// corners (points, lines) give nothing.
void triangulatePolygon(const std::vector<Vec3>& positions, std::span<const uint32_t> poly,
                        std::vector<std::array<uint32_t, 3>>& out);

}  // namespace sdft
