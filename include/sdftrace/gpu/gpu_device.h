// The GPU this process may use (issue 14, docs/gpu.md): whether this build has the CUDA backend
// (CMake's SDFT_CUDA) and whether a CUDA device is present. Plain C++: no CUDA header here.
#pragma once

#include <cstddef>
#include <string>

namespace sdft {

struct GpuInfo {
    bool built = false;    // this build has the CUDA backend
    bool present = false;  // and a device answered
    std::string name;      // e.g. "NVIDIA H200"
    int computeMajor = 0, computeMinor = 0;
    int multiprocessors = 0;
    size_t memoryBytes = 0;
    std::string why;  // when !present: what is missing, in one sentence
};

// Asked once per process (the first call initializes the CUDA runtime).
const GpuInfo& gpuInfo();

// Throws InputError "<what>: <why>" when no GPU can be used; `what` names the flag or key that
// asked for one (e.g. "--device cuda").
void requireGpu(const std::string& what);

}  // namespace sdft
