#include <cuda_runtime.h>

#include "sdftrace/core/error.h"
#include "sdftrace/gpu/gpu_device.h"

namespace sdft {

const GpuInfo& gpuInfo() {
    static const GpuInfo info = [] {
        GpuInfo i;
        i.built = true;
        int count = 0;
        const cudaError_t status = cudaGetDeviceCount(&count);
        if (status != cudaSuccess || count == 0) {
            i.why = std::string("no CUDA device is present (") +
                    (status != cudaSuccess ? cudaGetErrorString(status) : "none found") + ")";
            return i;
        }
        i.count = count;
        if (cudaGetDevice(&i.device) != cudaSuccess) i.device = 0;
        cudaDeviceProp prop{};
        if (cudaGetDeviceProperties(&prop, i.device) != cudaSuccess) {
            i.why = "the CUDA device did not answer";
            return i;
        }
        i.present = true;
        i.name = prop.name;
        i.computeMajor = prop.major;
        i.computeMinor = prop.minor;
        i.multiprocessors = prop.multiProcessorCount;
        i.memoryBytes = prop.totalGlobalMem;
        return i;
    }();
    return info;
}

int useGpuOfLocalRank(int localRank) {
    int count = 0;
    if (cudaGetDeviceCount(&count) != cudaSuccess || count == 0) return -1;
    const int device = gpuOfLocalRank(localRank, count);
    return cudaSetDevice(device) == cudaSuccess ? device : -1;
}

void requireGpu(const std::string& what) {
    if (!gpuInfo().present) throw InputError(what + ": " + gpuInfo().why);
}

}  // namespace sdft
