// The GPU renderer's kernels as a plugin (docs/decisions/0015): libsdftrace_gpu_kernels.so holds
// the 15 instantiations of launchDirect / launchPath (gpu_render_launch.cuh), the heaviest CUDA
// code by far, and hands them to the library as this table of function pointers. The library
// loads it on the first GPU render, so building the CLI (make run) does not wait for them.
// For .cu files only.
#pragma once

#include <cstddef>

#include "gpu_render_launch.cuh"

namespace sdft::gpu_render {

// The material register files the kernels are instantiated for (CMakeLists.txt generates one unit
// per entry and kind).
inline constexpr int kMaterialRegFiles[] = {1, 8, 16, 32, 64};
inline constexpr int kMaterialRegFileCount = 5;

using DirectLaunch = void (*)(const DirectPixelView&, const WhittedPixelView&, int, int,
                              const DirectOut&);
using PathLaunch = void (*)(const PathPixelView&, int, int, const DirectOut&);

struct KernelTable {
    // Bumped when the table changes; with `layout`, a plugin from another build is refused
    // rather than called with views of another shape.
    static constexpr int kVersion = 1;
    int version;
    size_t layout;
    DirectLaunch direct[kMaterialRegFileCount][2];  // [register file][Whitted rays compiled in]
    PathLaunch path[kMaterialRegFileCount];
};

// The sizes of what crosses the table, folded together: differs between builds whose views
// differ.
constexpr size_t kernelTableLayout() {
    return sizeof(DirectPixelView) * 1000003u + sizeof(WhittedPixelView) * 10007u +
           sizeof(PathPixelView) * 101u + sizeof(DirectOut);
}

// The index of register file `regs` in kMaterialRegFiles.
constexpr int materialRegFileIndex(int regs) {
    for (int i = 0; i < kMaterialRegFileCount; ++i)
        if (kMaterialRegFiles[i] == regs) return i;
    return kMaterialRegFileCount - 1;
}

}  // namespace sdft::gpu_render

// The plugin's one exported symbol.
extern "C" const sdft::gpu_render::KernelTable* sdftrace_gpu_kernels();
