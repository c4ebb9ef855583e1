// Jamriška 2010, §6's min/max buffer built on the device for a frame's camera: one thread per
// block of the DDA grid runs the CPU build's per-block functions (trace/minmax_buffer.h:
// splattedBlock, blockSquare) and splats its square with atomic min and max. The splatted
// distances are positive (a sphere reaching the camera plane sets `everything` instead), so their
// float order is the order of their bits as ints, and the buffer equals the CPU's bit for bit.
// For .cu files only.
#pragma once

#include "device_buffer.h"
#include "sdftrace/field/tape_view.h"
#include "sdftrace/trace/minmax_buffer.h"

namespace sdft::cuda {

class DeviceMinMax {
  public:
    // `field` is a device tape view, `grid` the index of the DDA grid in its grids and `host`
    // that grid's host view (its block counts). Launches on the default stream and waits for
    // the two counters (squares, everything).
    DeviceMinMax(const TapeView& field, int grid, const GridView& host, const Camera& camera,
                 int resolution) {
        build(field, grid, host, camera, resolution);
    }
    DeviceMinMax() = default;
    // The buffer anew for this camera, in the arrays of the last build where they are large
    // enough (a renderer's frames allocate once).
    void build(const TapeView& field, int grid, const GridView& host, const Camera& camera,
               int resolution);

    MinMaxView view() const { return m_view; }
    size_t squares() const { return m_squares; }

  private:
    DeviceArray<float> m_min, m_max;
    DeviceArray<unsigned> m_counters{2};
    MinMaxView m_view;
    size_t m_squares = 0;
};

}  // namespace sdft::cuda
