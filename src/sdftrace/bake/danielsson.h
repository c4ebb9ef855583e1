// Liktor 2008, §3.2: Danielsson's vector distance transform in 3D. A forward raster sweep in which
// each vertex adopts the nearest seed point among its 13 already-visited neighbours, then the same
// sweep backward over the other 13: two passes, linear time, "approximately right" distances
// (errors where the nearest point's Voronoi region is reached only diagonally). Serial: each pass
// depends on the vertices before it.
#pragma once

#include <vector>

#include "sdftrace/bake/surface_seeds.h"

namespace sdft {

std::vector<Vec3> danielssonTransform(const GridShape& shape, std::vector<Vec3> seeds);

}  // namespace sdft
