// Kernel launches, checked. Every launch of the backend goes through these:
// - no zero-size launch (an invalid configuration): nothing to do returns at once;
// - each kernel's stack (CUDA's per-thread stack limit, cudaLimitStackSize) is raised to what the
//   kernel's compiled code needs (cudaFuncGetAttributes: its local memory and stack frame) before
//   its first launch, and a device that cannot give it is an error naming the kernel;
// - a launch error names its kernel, and with SDFT_CUDA_SYNC=1 every launch is followed by a
//   synchronisation, so that a fault inside a kernel is reported under its name rather than at a
//   later, unrelated call. For .cu files only.
#pragma once

#include <cuda_runtime.h>

#include <cstdlib>
#include <mutex>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>

namespace sdft::cuda {

// SDFT_CUDA_SYNC=1 (read once): synchronise after every launch.
inline bool syncEveryLaunch() {
    static const bool sync = [] {
        const char* v = std::getenv("SDFT_CUDA_SYNC");
        return v && v[0] == '1';
    }();
    return sync;
}

// The stack limit raised, once per kernel, to the kernel's need.
inline void ensureStack(const char* name, const void* kernel) {
    static std::mutex mutex;
    static std::unordered_map<const void*, bool> done;
    std::lock_guard<std::mutex> lock(mutex);
    if (done.count(kernel)) return;
    cudaFuncAttributes attr{};
    cudaError_t e = cudaFuncGetAttributes(&attr, kernel);
    if (e != cudaSuccess)
        throw std::runtime_error(std::string("CUDA: ") + name + ": " + cudaGetErrorString(e));
    size_t limit = 0;
    e = cudaDeviceGetLimit(&limit, cudaLimitStackSize);
    if (e != cudaSuccess)
        throw std::runtime_error(std::string("CUDA: the stack limit: ") + cudaGetErrorString(e));
    if (attr.localSizeBytes > limit) {
        e = cudaDeviceSetLimit(cudaLimitStackSize, attr.localSizeBytes);
        if (e != cudaSuccess) {
            throw std::runtime_error(std::string("CUDA: ") + name + " needs " +
                                     std::to_string(attr.localSizeBytes) +
                                     " bytes of stack per thread, which the device cannot give (" +
                                     cudaGetErrorString(e) + ")");
        }
    }
    done[kernel] = true;
}

// After a launch: its error (a bad configuration, too many registers or too much stack) named by
// the kernel; with SDFT_CUDA_SYNC=1 also a fault while it ran.
inline void launched(const char* name) {
    cudaError_t e = cudaGetLastError();
    if (e != cudaSuccess)
        throw std::runtime_error(std::string("CUDA: launching ") + name + ": " +
                                 cudaGetErrorString(e));
    if (!syncEveryLaunch()) return;
    e = cudaDeviceSynchronize();
    if (e != cudaSuccess)
        throw std::runtime_error(std::string("CUDA: ") + name +
                                 " failed while running: " + cudaGetErrorString(e));
}

// `blocks` blocks of `threads` threads (none when blocks is 0).
template <class... Params, class... Args>
void launchBlocks(const char* name, size_t blocks, unsigned threads, void (*kernel)(Params...),
                  Args&&... args) {
    if (blocks == 0) return;
    if (blocks > 0x7fffffffu)
        throw std::runtime_error(std::string("CUDA: ") + name + ": " + std::to_string(blocks) +
                                 " blocks exceed the grid's limit of 2^31 - 1");
    ensureStack(name, reinterpret_cast<const void*>(kernel));
    kernel<<<static_cast<unsigned>(blocks), threads>>>(std::forward<Args>(args)...);
    launched(name);
}

// One thread per item of `count` (none when count is 0), in blocks of `threads`.
template <class... Params, class... Args>
void launch(const char* name, size_t count, unsigned threads, void (*kernel)(Params...),
            Args&&... args) {
    launchBlocks(name, (count + threads - 1) / threads, threads, kernel,
                 std::forward<Args>(args)...);
}

// One thread per pixel of a width x height image (none when either is 0), in `block` tiles.
template <class... Params, class... Args>
void launchImage(const char* name, int width, int height, dim3 block, void (*kernel)(Params...),
                 Args&&... args) {
    if (width <= 0 || height <= 0) return;
    const dim3 grid((width + block.x - 1) / block.x, (height + block.y - 1) / block.y);
    ensureStack(name, reinterpret_cast<const void*>(kernel));
    kernel<<<grid, block>>>(std::forward<Args>(args)...);
    launched(name);
}

}  // namespace sdft::cuda
