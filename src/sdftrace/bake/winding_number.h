// The generalized winding number of a triangle mesh (Jacobson et al. 2013): the sum of the solid
// angles its triangles subtend at p over 4 pi; about 1 inside and 0 outside, and still meaningful
// for open, messy meshes (scans with holes), where ray parity flips. Evaluated hierarchically
// (Barill et al. 2018): a BVH whose far nodes are replaced by their dipole (area-weighted normal
// sum at the area-weighted centroid); near nodes and leaves sum exact solid angles (Van Oosterom &
// Strackee).
#pragma once

#include <cmath>
#include <map>
#include <vector>

#include "sdftrace/bake/triangle_mesh.h"
#include "sdftrace/bake/winding_view.h"

namespace sdft {

// Exact solid angle of triangle (a, b, c) seen from p, signed by the winding (outward normals give
// a positive angle from inside).
double triangleSolidAngle(Vec3 p, Vec3 a, Vec3 b, Vec3 c);

class WindingNumber {
  public:
    // beta: a node is approximated when |p - centre| > beta * radius. First-order dipoles (no
    // higher-order terms) err by about 5% at Barill et al.'s beta = 2; 3 keeps it within 2.5%.
    explicit WindingNumber(const TriangleMesh& mesh, double beta = 3.0);

    double exact(Vec3 p) const;  // O(triangles): the reference
    // Hierarchical; leaves sum float solid angles with a polynomial atan2 (fastAtan2).
    double fast(Vec3 p) const { return fast(p, m_beta); }
    double fast(Vec3 p, double beta) const { return windingNumberFast(view(), p, beta); }
    // fast(p) > 1/2, first tried with a coarse beta (1.5, about 4x cheaper near the surface)
    // whose answer is taken when it is more than 0.3 from 1/2.
    bool inside(Vec3 p) const { return windingInside(view(), p, m_beta); }
    // The tree as plain data (winding_view.h), valid while this object lives.
    WindingView view() const {
        return {m_nodes.data(), static_cast<int>(m_nodes.size()), m_corners.data()};
    }
    double beta() const { return m_beta; }

  private:
    using Node = WindingNode;
    static int subtreeSize(int count, std::map<int, int>& sizes);
    // What the build reads: nodes per subtree size, and per triangle the sum of its corners (the
    // median split's key, 3x its centroid).
    struct BuildInput {
        const std::map<int, int>& sizes;
        const std::vector<Vec3>& sums;
    };
    void build(int first, int count, int index, const BuildInput& in);
    double exactRadius(int first, int count, double cx, double cy, double cz) const;

    const TriangleMesh& m_mesh;
    double m_beta;
    std::vector<Node> m_nodes;
    std::vector<int> m_order;
    std::vector<float> m_corners;  // 9 per triangle, in m_order
};

}  // namespace sdft
