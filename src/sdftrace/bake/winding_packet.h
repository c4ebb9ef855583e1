// The hierarchical winding number (winding_view.h) of several points at once, for the CPU's sign
// passes over rows of grid vertices: the points walk the tree together, each taking the nodes
// windingNumberFast would take in the same order (a point that settles a node by its dipole or
// its leaf drops out of that subtree), so each point's sum is the scalar sum bit for bit. The
// work per node is branch-free across the points, so that it vectorizes (built for AVX2 where the
// CPU has it, exec/simd.h).
#pragma once

#include <cstdint>

#include "sdftrace/bake/winding_view.h"

namespace sdft {

// windingInside (winding_view.h) of points p[0..n), any n: out[i] = 1 inside, 0 outside.
void windingInsideRow(const WindingView& w, const Vec3* p, int n, double beta, uint8_t* out);
// windingNumberFast of points p[0..n), bit for bit. Of the first 64 points, only those whose
// bits are set in `wanted` (the others' outputs are left as they are).
void windingNumberRow(const WindingView& w, const Vec3* p, int n, double beta, double* out,
                      uint64_t wanted = ~uint64_t{0});
// The same with the far terms summed in float (twice the lanes per instruction): within 1e-6 of
// windingNumberRow on the test meshes, not bit for bit; for callers that decide by a margin far
// above that.
void windingNumberRowFloat(const WindingView& w, const Vec3* p, int n, double beta, double* out,
                           uint64_t wanted = ~uint64_t{0});

}  // namespace sdft
