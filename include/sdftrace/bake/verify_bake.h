// How far a baked grid is from the exact SDF (`sdftrace bake --verify`, tests, benchmarks):
// |baked| - |exact| in voxels over the stored samples and over the narrow band, and the share of
// vertices whose sign differs.
#pragma once

#include <vector>

#include "sdftrace/field/grid.h"

namespace sdft {

struct BakeError {
    double mean = 0, p99 = 0, max = 0;  // of | |baked| - |exact| | in voxels
    size_t count = 0;
};

struct BakeVerification {
    BakeError all;   // every stored sample (dense: every vertex; sparse: surface blocks', against
                     // the exact distance clamped to the band as the grid stores it)
    BakeError band;  // those with |exact| < band
    // Over every vertex more than 1% of a voxel from the surface (sparse: flags count).
    size_t wrongSigns = 0, vertices = 0;
    double wrongSignShare() const { return vertices ? double(wrongSigns) / vertices : 0; }
};

// `exact`: the exact bake's samples on the grid's vertices (bakeExactSamples).
BakeVerification verifyBake(const Grid& grid, const std::vector<float>& exact, float bandVoxels);

}  // namespace sdft
