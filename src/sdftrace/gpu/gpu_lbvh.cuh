// The LBVH built on the device (Karras 2012; bake/lbvh.h): one thread per triangle for the keys,
// CUB's radix sort, one thread per internal node for the radix tree, one thread per leaf climbing
// to fill the boxes. The per-element bodies are lbvh.h's functions, which the CPU build (Lbvh)
// runs too. For .cu files only.
#pragma once

#include "device_buffer.h"
#include "sdftrace/bake/lbvh.h"

namespace sdft::cuda {

class DeviceLbvh {
  public:
    // positions and triangles are device arrays of the mesh; frame from lbvhFrame(mesh).
    DeviceLbvh(const Vec3* positions, const uint32_t* triangles, int count, LbvhFrame frame);

    LbvhView view() const { return {m_nodes.get(), m_triangles.get(), m_count}; }
    double buildMs() const { return m_buildMs; }
    size_t bytes() const {
        return m_nodes.size() * sizeof(LbvhNode) + m_triangles.size() * sizeof(LbvhTriangle);
    }

  private:
    int m_count = 0;
    DeviceArray<LbvhNode> m_nodes;
    DeviceArray<LbvhTriangle> m_triangles;
    double m_buildMs = 0;
};

}  // namespace sdft::cuda
