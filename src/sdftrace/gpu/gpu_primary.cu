#include <chrono>
#include <vector>

#include "cuda_launch.cuh"
#include "device_buffer.h"
#include "sdftrace/core/error.h"
#include "sdftrace/gpu/gpu_device.h"
#include "sdftrace/gpu/gpu_primary.h"

namespace sdft {

namespace {

// One thread per pixel, 16x8 blocks (neighbouring rays take similar paths through the tape).
__global__ void primaryKernel(PrimaryPixelView view, int width, int height, float* depth,
                              float* normal, int32_t* evaluations) {
    const int x = blockIdx.x * blockDim.x + threadIdx.x;
    const int y = blockIdx.y * blockDim.y + threadIdx.y;
    if (x >= width || y >= height) return;
    const PrimaryPixel px = tracePrimaryPixel(view, x, y);
    const size_t i = static_cast<size_t>(y) * width + x;
    depth[i] = px.trace.hit ? px.trace.t : kInfinity;
    normal[3 * i + 0] = px.normal.x;
    normal[3 * i + 1] = px.normal.y;
    normal[3 * i + 2] = px.normal.z;
    evaluations[i] = px.trace.evaluations;
}

}  // namespace

GpuPrimaryImage tracePrimaryGpu(const GpuTape& tape, const PrimaryPixelView& view, int width,
                                int height) {
    requireGpu("GPU primary rays");
    const auto begin = std::chrono::steady_clock::now();
    const size_t n = static_cast<size_t>(width) * height;
    GpuPrimaryImage out;
    out.width = width;
    out.height = height;
    cuda::DeviceArray<float> depth(n), normal(3 * n);
    cuda::DeviceArray<int32_t> evaluations(n);
    if (view.meshes.count > 0)
        throw InputError("GPU primary rays: triangle primaries render through GpuDirectRenderer");
    PrimaryPixelView v = view;
    v.field = tape.view();
    v.primaryField = v.field;
    cuda::DeviceArray<float> lo, hi;  // the view's min/max buffer, uploaded
    if (view.minMax.min) {
        const size_t cells = static_cast<size_t>(view.minMax.shape.w) * view.minMax.shape.h;
        lo = cuda::DeviceArray<float>(std::vector<float>(view.minMax.min, view.minMax.min + cells));
        hi = cuda::DeviceArray<float>(std::vector<float>(view.minMax.max, view.minMax.max + cells));
        v.minMax.min = lo.get();
        v.minMax.max = hi.get();
    }
    cuda::EventTimer timer;
    SDFT_CUDA_CHECK(cudaEventRecord(timer.start));
    cuda::launchImage("primaryKernel", width, height, dim3(16, 8), primaryKernel, v, width, height,
                      depth.get(), normal.get(), evaluations.get());
    SDFT_CUDA_CHECK(cudaEventRecord(timer.stop));
    out.kernelMs = timer.elapsedMs();
    depth.download(out.depth, n);
    normal.download(out.normal, 3 * n);
    evaluations.download(out.evaluations, n);
    out.frameMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
    return out;
}

}  // namespace sdft
