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
    // Each internal node's and each leaf's parent (-1: the root), kept from the build for
    // further bottom-up passes (the winding dipoles, bake/winding_lbvh.h). Empty below 2 triangles.
    const int32_t* parentOfNode() const { return m_parentOfNode.get(); }
    const int32_t* parentOfLeaf() const { return m_parentOfLeaf.get(); }
    double buildMs() const { return m_buildMs; }
    size_t bytes() const {
        return m_nodes.size() * sizeof(LbvhNode) + m_triangles.size() * sizeof(LbvhTriangle) +
               (m_parentOfNode.size() + m_parentOfLeaf.size()) * sizeof(int32_t);
    }

  private:
    int m_count = 0;
    DeviceArray<LbvhNode> m_nodes;
    DeviceArray<LbvhTriangle> m_triangles;
    DeviceArray<int32_t> m_parentOfNode, m_parentOfLeaf;
    double m_buildMs = 0;
};

}  // namespace sdft::cuda
