// The hierarchical generalized winding number (Barill et al. 2018) as plain data and a header
// function: the tree of WindingNumber (winding_number.h) as flat arrays, evaluated by the CPU's
// WindingNumber::fast and by one GPU thread per grid vertex (gpu/gpu_bake.cu) alike.
#pragma once

#include <cmath>

#include "sdftrace/math/vec.h"

namespace sdft {

// atan2 in float to 3e-7 rad (measured): Abramowitz & Stegun 4.4.49 for atan on [0, 1], with
// octant reduction.
// Branch-free (selects only), so that loops over it vectorize.
SDFT_HOST_DEVICE inline float fastAtan2(float y, float x) {
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

// The solid angle of triangle t (9 floats: its corners) seen from p, Van Oosterom & Strackee 1983
// in float, for the hierarchical sum's leaves.
SDFT_HOST_DEVICE inline float solidAngleFloat(Vec3 p, const float* t) {
    Vec3 a(t[0] - p.x, t[1] - p.y, t[2] - p.z), b(t[3] - p.x, t[4] - p.y, t[5] - p.z),
        c(t[6] - p.x, t[7] - p.y, t[8] - p.z);
    float la = length(a), lb = length(b), lc = length(c);
    float num = dot(a, cross(b, c));
    float den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    return 2.0f * fastAtan2(num, den);
}

struct WindingNode {
    Vec3 lo, hi;        // bounds of the triangles' vertices
    double cx, cy, cz;  // area-weighted centroid
    double nx, ny, nz;  // sum of area-weighted normals (the dipole)
    double area;        // of its triangles
    double radius;      // bounds the distance from the centroid to a vertex
    int left = -1, right = -1;
    int first = 0, count = 0;  // leaf: triangles [first, first + count) in tree order
};

// An inner node from its children l and r (at node indices `left`, `right`): moments added, the
// centroid area-weighted (their midpoint without area), the radius the tighter of the children's
// spheres and the farthest corner of the box (WindingNumber's median-split tree and LbvhWinding's
// tree alike).
SDFT_HOST_DEVICE inline WindingNode windingInner(const WindingNode& l, const WindingNode& r,
                                                 int left, int right) {
    WindingNode n;
    n.left = left;
    n.right = right;
    n.first = l.first < r.first ? l.first : r.first;
    n.count = l.count + r.count;
    n.lo = min(l.lo, r.lo);
    n.hi = max(l.hi, r.hi);
    n.area = l.area + r.area;
    if (n.area > 0) {
        n.cx = (l.area * l.cx + r.area * r.cx) / n.area;
        n.cy = (l.area * l.cy + r.area * r.cy) / n.area;
        n.cz = (l.area * l.cz + r.area * r.cz) / n.area;
    } else {
        n.cx = 0.5 * (l.cx + r.cx), n.cy = 0.5 * (l.cy + r.cy), n.cz = 0.5 * (l.cz + r.cz);
    }
    n.nx = l.nx + r.nx, n.ny = l.ny + r.ny, n.nz = l.nz + r.nz;
    const double ldx = l.cx - n.cx, ldy = l.cy - n.cy, ldz = l.cz - n.cz;
    const double rdx = r.cx - n.cx, rdy = r.cy - n.cy, rdz = r.cz - n.cz;
    const double reach = fmax(std::sqrt(ldx * ldx + ldy * ldy + ldz * ldz) + l.radius,
                              std::sqrt(rdx * rdx + rdy * rdy + rdz * rdz) + r.radius);
    const double fx = fmax(n.cx - n.lo.x, n.hi.x - n.cx), fy = fmax(n.cy - n.lo.y, n.hi.y - n.cy),
                 fz = fmax(n.cz - n.lo.z, n.hi.z - n.cz);
    n.radius = fmin(reach, std::sqrt(fx * fx + fy * fy + fz * fz));
    return n;
}

struct WindingView {
    const WindingNode* nodes = nullptr;  // the root first; none for an empty mesh
    int nodeCount = 0;
    const float* corners = nullptr;  // 9 per triangle, in tree order
};

// The traversal stack's entries: enough for the median-split tree of any mesh (its depth is log2
// of the triangle count) and for LbvhWinding's tree of 62-bit keys. A node whose children would
// not fit (a deeper tree) is summed exactly over its triangles instead, never dropped.
inline constexpr int kWindingStack = 128;

// The winding number at p: nodes farther than beta times their radius by their dipole
// (Barill et al. 2018, eq. 8), nearer leaves by their exact solid angles.
SDFT_HOST_DEVICE inline double windingNumberFast(const WindingView& w, Vec3 p, double beta) {
    if (w.nodeCount == 0) return 0;
    double sum = 0;
    int stack[kWindingStack];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const WindingNode& n = w.nodes[stack[--top]];
        double dx = n.cx - p.x, dy = n.cy - p.y, dz = n.cz - p.z;
        double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 > beta * beta * n.radius * n.radius) {
            // Far: the dipole term, Omega ~ (c - p).N / |c - p|^3 (Barill et al. 2018, eq. 8).
            sum += (dx * n.nx + dy * n.ny + dz * n.nz) / (d2 * std::sqrt(d2));
        } else if (n.left < 0 || top + 2 > kWindingStack) {
            // A leaf, or (stack full) the node's whole subtree: its triangles are [first,
            // first + count) in tree order.
            float leaf = 0;
            for (int i = n.first; i < n.first + n.count; ++i)
                leaf += solidAngleFloat(p, w.corners + 9 * static_cast<size_t>(i));
            sum += leaf;
        } else {
            stack[top++] = n.left;
            stack[top++] = n.right;
        }
    }
    return sum / 12.566370614359172;  // 4 pi
}

// windingNumberFast(p) > 1/2, first tried with a coarse beta (1.5, about 4x cheaper near the
// surface) whose answer is taken when it is more than 0.3 from 1/2.
SDFT_HOST_DEVICE inline bool windingInside(const WindingView& w, Vec3 p, double beta) {
    const double coarse = windingNumberFast(w, p, 1.5);
    if (std::fabs(coarse - 0.5) > 0.3) return coarse > 0.5;
    return windingNumberFast(w, p, beta) > 0.5;
}

}  // namespace sdft
