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

namespace sdft {

// Exact solid angle of triangle (a, b, c) seen from p, signed by the winding (outward normals give
// a positive angle from inside).
double triangleSolidAngle(Vec3 p, Vec3 a, Vec3 b, Vec3 c);

// atan2 in float to 3e-7 rad (measured): Abramowitz & Stegun 4.4.49 for atan on [0, 1], with
// octant reduction.
// Branch-free (selects only), so that loops over it vectorize.
inline float fastAtan2(float y, float x) {
    float ax = std::fabs(x), ay = std::fabs(y);
    float hi = ax > ay ? ax : ay, lo = ax > ay ? ay : ax;
    float a = lo / (hi > 1e-30f ? hi : 1e-30f), s = a * a;
    float r =
        ((((((((0.0028662257f * s - 0.0161657367f) * s + 0.0429096138f) * s - 0.0752896400f) * s +
             0.1065626393f) *
                s -
            0.1420889944f) *
               s +
           0.1999355085f) *
              s -
          0.3333314528f) *
         s) *
            a +
        a;
    r = ay > ax ? 1.57079637f - r : r;
    r = x < 0 ? kPi - r : r;
    return y < 0 ? -r : r;
}

class WindingNumber {
  public:
    // beta: a node is approximated when |p - centre| > beta * radius. First-order dipoles (no
    // higher-order terms) err by about 5% at Barill et al.'s beta = 2; 3 keeps it within 2.5%.
    explicit WindingNumber(const TriangleMesh& mesh, double beta = 3.0);

    double exact(Vec3 p) const;  // O(triangles): the reference
    // Hierarchical; leaves sum float solid angles with a polynomial atan2 (fastAtan2).
    double fast(Vec3 p) const { return fast(p, m_beta); }
    double fast(Vec3 p, double beta) const;
    // fast(p) > 1/2, first tried with a coarse beta (1.5, about 4x cheaper near the surface)
    // whose answer is taken when it is more than 0.3 from 1/2.
    bool inside(Vec3 p) const;

  private:
    struct Node {
        Vec3 lo, hi;        // bounds of the triangles' vertices
        double cx, cy, cz;  // area-weighted centroid
        double nx, ny, nz;  // sum of area-weighted normals (the dipole)
        double area;        // of its triangles
        double radius;      // bounds the distance from the centroid to a vertex
        int left = -1, right = -1;
        int first = 0, count = 0;  // leaf: triangles [first, first + count) of m_order
    };
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
