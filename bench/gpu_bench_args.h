// What the GPU benches share (gpu_primary_bench.cpp, gpu_direct_bench.cpp): their --runs and
// --cpu-runs flags, the medians they report, and the header naming both devices.
#pragma once

#include <tbb/task_arena.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "sdftrace/gpu/gpu_device.h"

namespace sdft::bench {

inline double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

struct GpuBenchArgs {
    int runs = 10, cpuRuns = 3;
    bool cpuOnly = false;  // --cpu-only: the CPU's figures where there is no GPU
    std::string scenes;    // --scenes a,b,c where the bench takes it
};

// False (after the usage line on stderr) on anything else than --runs N, --cpu-runs N and, when
// `scenes` names a default, --scenes LIST.
inline bool parseGpuBenchArgs(int argc, char** argv, const char* name, GpuBenchArgs& out,
                              const char* scenes = nullptr) {
    if (scenes) out.scenes = scenes;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--runs" && i + 1 < argc) {
            out.runs = std::max(1, std::atoi(argv[++i]));
        } else if (a == "--cpu-runs" && i + 1 < argc) {
            out.cpuRuns = std::max(1, std::atoi(argv[++i]));
        } else if (a == "--cpu-only") {
            out.cpuOnly = true;
        } else if (scenes && a == "--scenes" && i + 1 < argc) {
            out.scenes = argv[++i];
        } else {
            std::fprintf(stderr, "usage: %s [--runs N] [--cpu-runs N] [--cpu-only]%s%s%s\n", name,
                         scenes ? " [--scenes " : "", scenes ? scenes : "", scenes ? "]" : "");
            return false;
        }
    }
    const GpuInfo& gpu = gpuInfo();
    std::printf("GPU: %s\n", gpu.present ? gpu.name.c_str() : gpu.why.c_str());
    // Without a GPU there is nothing to time (scripts/gpu-check.sh --dry-run runs the benches
    // anyway, to see that they start), unless the CPU's side is asked for.
    if (!gpu.present && !out.cpuOnly) {
        std::printf("no GPU: nothing to time (--cpu-only times the CPU's side alone)\n");
        std::fflush(stdout);
        std::exit(0);
    }
    std::printf("CPU: %d hardware threads\n\n", tbb::this_task_arena::max_concurrency());
    return true;
}

}  // namespace sdft::bench
