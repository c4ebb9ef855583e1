// A complete block grid (Grid::completeFromDense) on the GPU, refreshed there every frame from a
// field on the device: RTSDF's per-frame grid (Tan et al. 2022, §2.5.1) without its round trip
// through the host. One thread per block runs refreshCompleteBlock (field/complete_block.h, the
// body Grid::refreshComplete runs on the CPU); the skip tables' Chebyshev distances are dilations
// on the device (equal to Grid::computeBlockSkip's); the global Lipschitz bound is a reduction.
// Plain C++: no CUDA header here; without the CUDA backend every call is one clear error.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "sdftrace/field/grid.h"

namespace sdft {

// GPU milliseconds of a refresh (CUDA events) and its wall time.
struct GpuRefreshTimes {
    double blocksMs = 0;  // samples, cell masks and gradient bounds
    double skipMs = 0;    // the global bound, block and tile skip distances
    double totalMs = 0;   // wall, the bound's 4-byte copy back included
};

// The arrays a refresh writes, copied back (tests): Grid's arrays of the same name.
struct GpuCompleteGridArrays {
    std::vector<float> blockSamples;
    std::vector<uint64_t> cellMasks;
    std::vector<uint8_t> blockSkip, tileSkip, blockLipschitz, tileLipschitz;
    float lipschitz = 1;
};

class GpuCompleteGrid {
  public:
    // Uploads complete grid `layout` (its tables and values). Throws InputError when no GPU can
    // be used or `layout` is not a complete grid.
    explicit GpuCompleteGrid(const Grid& layout);
    ~GpuCompleteGrid();
    GpuCompleteGrid(GpuCompleteGrid&&) noexcept;
    GpuCompleteGrid& operator=(GpuCompleteGrid&&) noexcept;

    // The grid Grid::refreshComplete builds from `deviceDense` (the layout's vertexCount()
    // floats on the device, x fastest: GpuMeshBaker::accumulateOnDevice's field), in place.
    void refresh(const float* deviceDense, GpuRefreshTimes* times = nullptr);
    // The same from a host field (uploaded first; tests).
    void refreshFromHost(const std::vector<float>& dense, GpuRefreshTimes* times = nullptr);
    // The grid's view: device pointers, its bound the last refresh's.
    const GridView& view() const;
    GpuCompleteGridArrays download() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace sdft
