// The GPU renderer's kernels as launch functions, one per kernel and material register file
// (gpu_render_kernels.cuh defines them). Each is compiled in a translation unit of its own that
// CMake generates (CMakeLists.txt: SDFT_GPU_KERNEL_UNITS): the 15 instantiations of the two
// kernels compile in parallel rather than as one six-minute unit. For .cu files only.
#pragma once

#include <cstdint>

#include "sdftrace/render/direct_pixel.h"
#include "sdftrace/render/path_pixel.h"
#include "sdftrace/render/whitted_pixel.h"

namespace sdft::gpu_render {

// The film's arrays on the device, in the film's layout; per pixel the counters a summary needs.
struct DirectOut {
    float *color, *depth, *normal, *steps, *error, *shadow, *ao, *travSteps, *isectTests;
    uint32_t* counters;  // kCounters per pixel: shadow and AO evaluations, fallbacks, hits,
                         // secondary rays, their evaluations, self-intersections; then direct: a
                         // triangle hit (its normal is the triangle's); paths: primary
                         // evaluations, shadow rays, normal evaluations of every sample
};
inline constexpr int kCounters = 10;

// One thread per pixel, 16x8 blocks, on the default stream. kMaterialRegs: the material register
// file of the material blend (1 where the plan has one uniform material: the blend is never
// evaluated); kWhitted: Whitted rays and their stack compiled in (the plan has mirrors or
// dielectrics).
template <int kMaterialRegs, bool kWhitted>
void launchDirect(const DirectPixelView& view, const WhittedPixelView& whitted, int width,
                  int height, const DirectOut& out);
template <int kMaterialRegs>
void launchPath(const PathPixelView& view, int width, int height, const DirectOut& out);

}  // namespace sdft::gpu_render
