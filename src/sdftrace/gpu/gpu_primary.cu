#include <chrono>

#include "cuda_check.h"
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

template <class T>
struct DeviceArray {
    T* ptr = nullptr;
    explicit DeviceArray(size_t n) { SDFT_CUDA_CHECK(cudaMalloc(&ptr, n * sizeof(T))); }
    ~DeviceArray() { cudaFree(ptr); }
    DeviceArray(const DeviceArray&) = delete;
    DeviceArray& operator=(const DeviceArray&) = delete;
};

struct Events {
    cudaEvent_t start = nullptr, stop = nullptr;
    Events() {
        SDFT_CUDA_CHECK(cudaEventCreate(&start));
        SDFT_CUDA_CHECK(cudaEventCreate(&stop));
    }
    ~Events() {
        cudaEventDestroy(start);
        cudaEventDestroy(stop);
    }
};

}  // namespace

GpuPrimaryImage tracePrimaryGpu(const GpuTape& tape, const PrimaryPixelView& view, int width,
                                int height) {
    requireGpu("GPU primary rays");
    const auto begin = std::chrono::steady_clock::now();
    const size_t n = static_cast<size_t>(width) * height;
    GpuPrimaryImage out;
    out.width = width;
    out.height = height;
    DeviceArray<float> depth(n), normal(3 * n);
    DeviceArray<int32_t> evaluations(n);
    PrimaryPixelView v = view;
    v.field = tape.view();
    const dim3 block(16, 8);
    const dim3 grid((width + block.x - 1) / block.x, (height + block.y - 1) / block.y);
    Events ev;
    SDFT_CUDA_CHECK(cudaEventRecord(ev.start));
    primaryKernel<<<grid, block>>>(v, width, height, depth.ptr, normal.ptr, evaluations.ptr);
    SDFT_CUDA_CHECK(cudaGetLastError());
    SDFT_CUDA_CHECK(cudaEventRecord(ev.stop));
    SDFT_CUDA_CHECK(cudaEventSynchronize(ev.stop));
    float ms = 0;
    SDFT_CUDA_CHECK(cudaEventElapsedTime(&ms, ev.start, ev.stop));
    out.kernelMs = ms;
    out.depth.resize(n);
    out.normal.resize(3 * n);
    out.evaluations.resize(n);
    SDFT_CUDA_CHECK(
        cudaMemcpy(out.depth.data(), depth.ptr, n * sizeof(float), cudaMemcpyDeviceToHost));
    SDFT_CUDA_CHECK(
        cudaMemcpy(out.normal.data(), normal.ptr, 3 * n * sizeof(float), cudaMemcpyDeviceToHost));
    SDFT_CUDA_CHECK(cudaMemcpy(out.evaluations.data(), evaluations.ptr, n * sizeof(int32_t),
                               cudaMemcpyDeviceToHost));
    out.frameMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
    return out;
}

}  // namespace sdft
