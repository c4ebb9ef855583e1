// CUDA runtime calls checked: a failure throws std::runtime_error naming the call and CUDA's
// message (the CLI prints it as one line). For .cu files only.
#pragma once

#include <cuda_runtime.h>

#include <stdexcept>
#include <string>

namespace sdft::cuda {

inline void check(cudaError_t status, const char* call) {
    if (status != cudaSuccess)
        throw std::runtime_error(std::string("CUDA: ") + call + ": " + cudaGetErrorString(status));
}

}  // namespace sdft::cuda

#define SDFT_CUDA_CHECK(call) ::sdft::cuda::check((call), #call)
