// A tape copied to the GPU: its instructions, constants and every grid's buffers uploaded once,
// and a TapeView of device pointers handed to kernels (NanoVDB's GridHandle is the model: the
// host owns the upload, kernels see plain views). The CPU's Tape stays the one compiled from the
// scene; this is its device twin.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "sdftrace/field/tape.h"
#include "sdftrace/field/tape_view.h"

namespace sdft {

// A grid of the tape that is already on the device (a GpuCompleteGrid refreshed there every
// frame): the tape's copy reads `view` instead of an upload of the grid's arrays.
struct GpuGridBinding {
    const Grid* grid = nullptr;  // one of tape.grids()
    GridView view;               // device pointers
};

class GpuTape {
  public:
    // Throws InputError when this build has no CUDA backend or no GPU is present, and a
    // std::runtime_error naming the CUDA call that failed (out of device memory, for one).
    explicit GpuTape(const Tape& tape, const std::vector<GpuGridBinding>& bound = {});
    // A bound grid's view anew (a refresh changed its Lipschitz bound): one small copy.
    void rebind(const GpuGridBinding& binding);
    ~GpuTape();
    GpuTape(GpuTape&&) noexcept;
    GpuTape& operator=(GpuTape&&) noexcept;

    // Device pointers: valid on the GPU only, while this object lives.
    const TapeView& view() const;
    size_t deviceBytes() const;  // everything uploaded

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace sdft
