// Primary rays on the GPU (issue 14): one thread per pixel runs tracePrimaryPixel
// (render/primary_pixel.h), the function the CPU tests hold to the CPU renderer, over the tape's
// device copy. Depth, normal and evaluation counts come back as the CPU renderer's AOVs.
#pragma once

#include <cstdint>
#include <vector>

#include "sdftrace/gpu/gpu_tape.h"
#include "sdftrace/render/primary_pixel.h"

namespace sdft {

struct GpuPrimaryImage {
    int width = 0, height = 0;
    std::vector<float> depth;          // t along the unit primary ray, +inf on a miss
    std::vector<float> normal;         // 3 per pixel, zero on a miss
    std::vector<int32_t> evaluations;  // field evaluations of the pixel's ray
    double kernelMs = 0;               // the kernel alone (CUDA events)
    double frameMs = 0;                // launch, kernel and the copies back
};

// `view`'s field is replaced by `tape`'s device view; a min/max buffer in `view.minMax` (host
// arrays, MinMaxBuffer::view) is uploaded; everything else of it is passed by value.
GpuPrimaryImage tracePrimaryGpu(const GpuTape& tape, const PrimaryPixelView& view, int width,
                                int height);

// Jamriška §6's min/max buffer built on the device (gpu_minmax.cuh: a thread per block, the CPU
// build's per-block functions, atomic min and max), brought back for comparison with
// MinMaxBuffer::build: the same squares, so the same buffer bit for bit.
struct GpuMinMax {
    MinMaxShape shape;
    std::vector<float> min, max;  // per buffer pixel, row by row (+inf / -inf where uncovered)
    bool everything = false;
    size_t squares = 0;
    double ms = 0;  // the build on the device (CUDA events)
};
// `grid`: the index in `tape`'s grids of the grid whose host view is `host`.
GpuMinMax buildMinMaxGpu(const GpuTape& tape, int grid, const GridView& host, const Camera& camera,
                         int resolution);

}  // namespace sdft
