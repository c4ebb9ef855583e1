// The exact Euclidean distance transform of the seed vertices by three separable 1D passes
// (Felzenszwalb and Huttenlocher 2012: lower envelopes of parabolas; Saito and Toriwaki 1994),
// carrying the index of the nearest seed (a feature transform). Linear time, parallel over lines,
// and exact where Danielsson's two sweeps are "approximately right" (Liktor §3.2): the better
// baseline. Each vertex then measures to the surface point its nearest seed holds.
#pragma once

#include <vector>

#include "sdftrace/bake/surface_seeds.h"

namespace sdft {

std::vector<Vec3> separableEdt(const GridShape& shape, const std::vector<Vec3>& seeds,
                               int threads = 0);

}  // namespace sdft
