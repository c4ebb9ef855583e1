// The GPU renderer's two kernels, one thread per pixel, their bodies the CPU-tested header
// functions (shadePixel, pathRadiance), and the launch functions of gpu_render_launch.cuh. Included
// by CMake's generated units only, each instantiating one launch function (SDFT_GPU_KERNEL).
#pragma once

#include "cuda_check.h"
#include "cuda_launch.cuh"
#include "gpu_render_launch.cuh"

namespace sdft::gpu_render {

namespace {

// One thread per pixel, 16x8 blocks. kMaterialRegs: the material register file of the material
// blend (1 where the plan has one uniform material: the blend is never evaluated). kWhitted: the
// plan has mirrors or dielectrics (Whitted rays and their stack are compiled in).
template <int kMaterialRegs, bool kWhitted>
__global__ void directKernel(DirectPixelView view, WhittedPixelView whitted, int width, int height,
                             DirectOut out) {
    const int x = blockIdx.x * blockDim.x + threadIdx.x;
    const int y = blockIdx.y * blockDim.y + threadIdx.y;
    if (x >= width || y >= height) return;
    const DirectPixel px = shadePixel<kMaterialRegs, kWhitted>(view, whitted, x, y);
    const size_t i = static_cast<size_t>(y) * width + x;
    const bool hit = px.primary.trace.hit;
    for (int a = 0; a < 3; ++a) {
        out.color[3 * i + a] = px.color[a];
        out.normal[3 * i + a] = hit ? px.primary.normal[a] : 0.0f;
    }
    out.depth[i] = hit ? px.primary.trace.t : kInfinity;
    out.steps[i] = static_cast<float>(px.primary.trace.evaluations);
    out.error[i] = hit ? px.primary.trace.value : 0.0f;
    out.shadow[i] = px.shadow;
    out.ao[i] = px.ao;
    out.travSteps[i] = static_cast<float>(px.primary.traversalSteps);
    out.isectTests[i] = static_cast<float>(px.primary.intersectionTests);
    uint32_t* c = out.counters + kCounters * i;
    c[0] = px.shadowEvaluations;
    c[1] = px.aoEvaluations;
    c[2] = static_cast<uint32_t>(px.primary.trace.fallbacks);
    c[3] = hit ? 1u : 0u;
    c[4] = px.secondaryRays;
    c[5] = px.secondaryEvaluations;
    c[6] = px.selfIntersections;
    c[7] = hit && px.primary.bias > 0 ? 1u : 0u;
}

// The per-pixel material table (textures included) as pathRadiance's material lookup.
template <int kMaterialRegs>
struct TableMaterial {
    const DirectPixelView* view;
    SDFT_HOST_DEVICE PixelMaterial operator()(Vec3 p, Vec3 n) const {
        return direct_pixel::materialAt<kMaterialRegs>(*view, p, n);
    }
};

// The path tracer, one thread per pixel running its samples (path_pixel.h): colour the samples'
// mean, depth, normal and steps the first sample's.
template <int kMaterialRegs>
__global__ void pathKernel(PathPixelView view, int width, int height, DirectOut out) {
    const int x = blockIdx.x * blockDim.x + threadIdx.x;
    const int y = blockIdx.y * blockDim.y + threadIdx.y;
    if (x >= width || y >= height) return;
    const TableMaterial<kMaterialRegs> materials{&view.direct};
    PathCounters pc;
    Vec3 sum(0.0f), normal(0.0f);
    float depth = kInfinity;
    int steps = 0;
    for (int k = 0; k < view.samplesPerPixel; ++k)
        sum += pathRadiance(view, materials, x, y, k, pc, k == 0 ? &depth : nullptr,
                            k == 0 ? &normal : nullptr, k == 0 ? &steps : nullptr);
    const Vec3 color = sum / static_cast<float>(view.samplesPerPixel);
    const size_t i = static_cast<size_t>(y) * width + x;
    for (int a = 0; a < 3; ++a) {
        out.color[3 * i + a] = color[a];
        out.normal[3 * i + a] = normal[a];
    }
    out.depth[i] = depth;
    out.steps[i] = static_cast<float>(steps);
    out.error[i] = 0;
    out.shadow[i] = 1;
    out.ao[i] = 1;
    out.travSteps[i] = 0;
    out.isectTests[i] = 0;
    uint32_t* c = out.counters + kCounters * i;
    c[0] = static_cast<uint32_t>(pc.shadowEvaluations);
    c[1] = 0;
    c[2] = 0;
    c[3] = static_cast<uint32_t>(pc.hits);
    c[4] = static_cast<uint32_t>(pc.secondaryRays);
    c[5] = static_cast<uint32_t>(pc.secondaryEvaluations);
    c[6] = 0;
    c[7] = static_cast<uint32_t>(pc.primaryEvaluations);
    c[8] = static_cast<uint32_t>(pc.shadowRays);
    c[9] = static_cast<uint32_t>(pc.normalEvaluations);
}

}  // namespace

template <int kMaterialRegs, bool kWhitted>
void launchDirect(const DirectPixelView& view, const WhittedPixelView& whitted, int width,
                  int height, const DirectOut& out) {
    cuda::launchImage(kWhitted ? "directKernel (Whitted)" : "directKernel", width, height,
                      dim3(16, 8), directKernel<kMaterialRegs, kWhitted>, view, whitted, width,
                      height, out);
}

template <int kMaterialRegs>
void launchPath(const PathPixelView& view, int width, int height, const DirectOut& out) {
    cuda::launchImage("pathKernel", width, height, dim3(16, 8), pathKernel<kMaterialRegs>, view,
                      width, height, out);
}

}  // namespace sdft::gpu_render
