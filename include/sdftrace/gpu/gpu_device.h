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
    int device = 0, count = 0;  // the device this process uses, of `count` present
    std::string why;            // when !present: what is missing, in one sentence
};

// Asked once per process (the first call initializes the CUDA runtime): the device this process
// uses (useGpuOfLocalRank's, or the first).
const GpuInfo& gpuInfo();

// One GPU per rank: the ranks of a job on one machine take its `count` GPUs in turn, local rank r
// the device r mod count (-1 without any).
inline int gpuOfLocalRank(int localRank, int count) {
    return count > 0 ? (localRank < 0 ? 0 : localRank) % count : -1;
}
// Makes this process use gpuOfLocalRank(localRank, <the devices present>) for all its GPU work;
// called before any other GPU call (gpuInfo() included), by each rank of an mpirun job that
// renders on GPUs. Returns the device's index, -1 where none is present or this build has no
// CUDA backend (gpuInfo().why says which).
int useGpuOfLocalRank(int localRank);

// Throws InputError "<what>: <why>" when no GPU can be used; `what` names the flag or key that
// asked for one (e.g. "--device cuda").
void requireGpu(const std::string& what);

}  // namespace sdft
