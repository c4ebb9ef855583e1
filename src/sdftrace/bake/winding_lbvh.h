// Barill et al. 2018's dipole tree over an LBVH's radix tree (Karras 2012), for meshes that move
// every frame (RTSDF §2.5): the median-split tree of WindingNumber is built on the host, where the
// LBVH is built on the device in a fraction of a millisecond; its nodes' moments (area,
// area-weighted centroid, dipole, radius) follow in one more bottom-up pass. Leaves hold one
// triangle each, in the LBVH's key order. The per-node functions below are the whole build: run
// in post order by LbvhWinding on the CPU and by one GPU thread per leaf climbing to the root
// (gpu/gpu_bake.cu, the LBVH's box pass). The tree is evaluated by winding_view.h's functions.
#pragma once

#include <cmath>
#include <vector>

#include "sdftrace/bake/lbvh.h"
#include "sdftrace/bake/winding_view.h"

namespace sdft {

// The winding node of LBVH child code `child` (~leaf below 0, else an internal node) of a tree
// over `count` triangles: internal nodes keep their index (the root is 0), leaf j follows them at
// count - 1 + j.
SDFT_HOST_DEVICE inline int windingNodeOfLbvhChild(int32_t child, int count) {
    return child < 0 ? count - 1 + ~child : child;
}

// The leaf of triangle j in key order (WindingNumber's leaf of one triangle).
SDFT_HOST_DEVICE inline WindingNode windingLeaf(const LbvhTriangle& t, int j) {
    WindingNode n;
    n.first = j;
    n.count = 1;
    n.lo = min(t.a, min(t.b, t.c));
    n.hi = max(t.a, max(t.b, t.c));
    const double ux = double(t.b.x) - t.a.x, uy = double(t.b.y) - t.a.y, uz = double(t.b.z) - t.a.z;
    const double vx = double(t.c.x) - t.a.x, vy = double(t.c.y) - t.a.y, vz = double(t.c.z) - t.a.z;
    const double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
    n.area = 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
    n.nx = 0.5 * cx, n.ny = 0.5 * cy, n.nz = 0.5 * cz;
    const Vec3 centroid = (t.a + t.b + t.c) / 3.0f;
    n.cx = centroid.x, n.cy = centroid.y, n.cz = centroid.z;
    double r2 = 0;
    const Vec3 corners[3] = {t.a, t.b, t.c};
    for (const Vec3& p : corners) {
        const double dx = p.x - n.cx, dy = p.y - n.cy, dz = p.z - n.cz;
        r2 = fmax(r2, dx * dx + dy * dy + dz * dz);
    }
    n.radius = std::sqrt(r2);
    return n;
}

// Triangle j's corners in key order, as WindingView::corners holds them.
SDFT_HOST_DEVICE inline void windingCorners(const LbvhTriangle& t, float* out) {
    const Vec3 v[3] = {t.a, t.b, t.c};
    for (int k = 0; k < 3; ++k) {
        out[3 * k] = v[k].x;
        out[3 * k + 1] = v[k].y;
        out[3 * k + 2] = v[k].z;
    }
}

// The tree built on the CPU from an LBVH (the GPU's twin, and its reference in the tests).
class LbvhWinding {
  public:
    explicit LbvhWinding(const LbvhView& lbvh);
    WindingView view() const {
        return {m_nodes.data(), static_cast<int>(m_nodes.size()), m_corners.data()};
    }
    const std::vector<WindingNode>& nodes() const { return m_nodes; }

  private:
    std::vector<WindingNode> m_nodes;
    std::vector<float> m_corners;
};

}  // namespace sdft
