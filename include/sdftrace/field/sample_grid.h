// Sampling a field into a grid (Liktor 2008, §3.1: the sampling stage of preprocessing): the value
// f/L at every grid vertex, in parallel, one batch per row.
#pragma once

#include "sdftrace/field/grid.h"
#include "sdftrace/field/tape.h"

namespace sdft {

struct SampleOptions {
    int resolution = 128;  // cells along the longest axis of the region
    GridKind kind = GridKind::Sparse;
    int blockSize = 4;        // sparse: 4 or 8
    float bandVoxels = 3;     // sparse: blocks farther than this from the surface are dropped
    float paddingVoxels = 2;  // empty voxels around the region, beyond the band
    int threads = 0;          // 0 = all
    bool progress = false;    // a percentage on stderr while sampling
};

// The grid shape covering `region` (finite) plus padding at `resolution` cells along its longest
// axis, the other axes in proportion.
GridShape gridShapeFor(const Bounds3& region, const SampleOptions& options);

// Samples tape.eval(p) / tape.lipschitz() at every vertex of `shape`.
class Progress;
// `progress`, when given, advances once per row of vertices (shape.vertices(1) * vertices(2)).
std::vector<float> sampleVertices(const Tape& tape, const GridShape& shape, int threads = 0,
                                  Progress* progress = nullptr);

// gridShapeFor + sampleVertices + the layout the options ask for. `region` must be finite.
Grid sampleGrid(const Tape& tape, const Bounds3& region, const SampleOptions& options);

}  // namespace sdft
