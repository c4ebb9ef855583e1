// A grid of a scene whose current values live on the GPU, not in the host Grid that stands for it
// in the node tree (RTSDF's per-frame grid under `render --device cuda`: the field is accumulated
// and the complete block grid refreshed on the device every frame, gpu/gpu_bake.h). The host grid
// keeps the layout and an earlier frame's values: only a GPU renderer, which binds the device
// grid in its place, may render a plan that holds one; the CPU renderer refuses it.
#pragma once

#include <memory>
#include <vector>

#include "sdftrace/field/grid.h"

namespace sdft {

struct RtsdfDeviceState;  // gpu/gpu_bake.h: the baker and the device grid

struct DeviceResidentGrid {
    const Grid* grid = nullptr;  // the host stand-in in the node tree
    std::shared_ptr<RtsdfDeviceState> state;
};

// The device state of `grid` among `grids`; none where its values are on the host.
inline std::shared_ptr<RtsdfDeviceState> deviceStateOf(const std::vector<DeviceResidentGrid>& grids,
                                                       const Grid* grid) {
    for (const DeviceResidentGrid& d : grids)
        if (d.grid == grid) return d.state;
    return nullptr;
}

}  // namespace sdft
