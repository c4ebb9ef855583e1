// How far a baked grid is from the exact SDF (`sdftrace bake --verify`, tests, benchmarks):
// |baked| - |exact| in voxels over the stored samples and over the narrow band, and the share of
// vertices whose sign differs.
#pragma once

#include <vector>

#include "sdftrace/field/grid.h"
#include "sdftrace/field/tape.h"

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
    // Vertices off the surface (beyond 1% of a voxel) whose sign is wrong, and those of them
    // beyond half a voxel, where a wrong sign moves the surface visibly.
    size_t wrongSigns = 0, wrongSignsFar = 0, vertices = 0;
    double wrongSignShare() const { return vertices ? double(wrongSigns) / vertices : 0; }
};

// `exact`: the exact bake's samples on the grid's vertices (bakeExactSamples).
BakeVerification verifyBake(const Grid& grid, const std::vector<float>& exact, float bandVoxels);

// A grid sampled from a field (`sdftrace bake scene.json --verify`) against the field itself,
// f/L: at the vertices (the sampling: zero up to the sparse grid's clamp to the band) and at cell
// centres, where the trilinear reconstruction the tracers use stands in for the field between
// samples (`band` there: centres with |f/L| < band; at most about 4M centres, evenly strided).
struct FieldVerification {
    BakeVerification vertices;
    BakeError centres;
    size_t wrongSignCentres = 0, signedCentres = 0;  // centres more than 1% of a voxel from f = 0
};
FieldVerification verifyAgainstField(const Grid& grid, const Tape& tape, float bandVoxels,
                                     int threads = 0);

}  // namespace sdft
