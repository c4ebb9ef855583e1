// A linear BVH over a triangle mesh (Karras 2012, "Maximizing Parallelism in the Construction of
// BVHs, Octrees, and k-d Trees", §3-4): the triangles sorted by the 30-bit Morton code of their
// centroid (the index below it makes every key unique), the binary radix tree over the sorted keys
// built one internal node per thread, and the boxes filled bottom-up, each node by the second of
// its children to finish. Every step is a header function run per element: by TBB on the CPU
// (Lbvh, bake/lbvh.cpp) and by one CUDA thread per element on the GPU (gpu/gpu_lbvh.cu); the
// first-hit traversal below is the same function on both. Why an LBVH and not a SAH tree:
// docs/decisions/0013-lbvh-for-gpu-rays.md.
#pragma once

#include <cstdint>
#include <vector>

#include "sdftrace/bake/triangle_mesh.h"
#include "sdftrace/math/ray.h"

namespace sdft {

// An internal node: its box and its two children. A child >= 0 is an internal node, a child < 0
// the leaf ~child (one triangle, in key order). Node 0 is the root.
struct LbvhNode {
    Vec3 lo;
    int32_t left = 0;
    Vec3 hi;
    int32_t right = 0;
};

// A triangle in key order: its corners and its index in the mesh.
struct LbvhTriangle {
    Vec3 a, b, c;
    uint32_t id = 0;
};

// The tree as plain data: count - 1 internal nodes (none for a single triangle) and count leaves.
struct LbvhView {
    const LbvhNode* nodes = nullptr;
    const LbvhTriangle* triangles = nullptr;
    int count = 0;
};

// A ray's first hit: t (+inf on a miss), whether it struck the front (against the
// counter-clockwise normal, as MeshBvh::Hit), the mesh's triangle index and the barycentric
// coordinates of a (1 - u - v) + b u + c v.
struct LbvhHit {
    float t = kInfinity;
    bool front = false;
    uint32_t triangle = 0;
    float u = 0, v = 0;
};

// Builds are limited to this many triangles (the tree's child indices and Karras' doubling search
// stay within int32).
inline constexpr int kMaxLbvhTriangles = 1 << 30;

// 10 bits spread to every third bit of 30 (Karras 2012, §4's Morton codes).
SDFT_HOST_DEVICE inline uint32_t spreadBits10(uint32_t v) {
    v = (v * 0x00010001u) & 0xFF0000FFu;
    v = (v * 0x00000101u) & 0x0F00F00Fu;
    v = (v * 0x00000011u) & 0xC30C30C3u;
    v = (v * 0x00000005u) & 0x49249249u;
    return v;
}

// The sort key of triangle `index` (a, b, c): the Morton code of its centroid in the box from `lo`
// with 1 / extent `invExtent`, above the index (unique keys: Karras §4's tie rule for free).
SDFT_HOST_DEVICE inline uint64_t lbvhKey(Vec3 a, Vec3 b, Vec3 c, Vec3 lo, Vec3 invExtent,
                                         uint32_t index) {
    const Vec3 q = ((a + b + c) * (1.0f / 3.0f) - lo) * invExtent;
    uint32_t code = 0;
    for (int axis = 0; axis < 3; ++axis) {
        const float x = clampf(q[axis] * 1024.0f, 0.0f, 1023.0f);
        code |= spreadBits10(static_cast<uint32_t>(x)) << (2 - axis);
    }
    return (static_cast<uint64_t>(code) << 32) | index;
}

SDFT_HOST_DEVICE inline int countLeadingZeros64(uint64_t x) {
#if defined(__CUDA_ARCH__)
    return __clzll(static_cast<long long>(x));
#else
    return x == 0 ? 64 : __builtin_clzll(x);
#endif
}

// δ(i, j) of Karras §4: the length of the common prefix of keys i and j, -1 when j is outside
// [0, n).
SDFT_HOST_DEVICE inline int lbvhPrefix(const uint64_t* keys, int n, int i, int j) {
    if (j < 0 || j >= n) return -1;
    return countLeadingZeros64(keys[i] ^ keys[j]);
}

// The two children of internal node i of the radix tree over n sorted, unique keys (Karras 2012,
// Figure 4): the direction of its range, the range's other end by an exponential then a binary
// search, and the split (the highest differing bit) by a binary search inside it.
struct LbvhChildren {
    int32_t left, right;
};
SDFT_HOST_DEVICE inline LbvhChildren lbvhInternalNode(const uint64_t* keys, int n, int i) {
    const int d = lbvhPrefix(keys, n, i, i + 1) > lbvhPrefix(keys, n, i, i - 1) ? 1 : -1;
    const int minPrefix = lbvhPrefix(keys, n, i, i - d);
    int maxLength = 2;
    while (lbvhPrefix(keys, n, i, i + maxLength * d) > minPrefix) maxLength *= 2;
    int length = 0;
    for (int t = maxLength / 2; t >= 1; t /= 2)
        if (lbvhPrefix(keys, n, i, i + (length + t) * d) > minPrefix) length += t;
    const int j = i + length * d;
    const int nodePrefix = lbvhPrefix(keys, n, i, j);
    int split = 0, step = length;
    do {
        step = (step + 1) >> 1;
        if (split + step < length && lbvhPrefix(keys, n, i, i + (split + step) * d) > nodePrefix)
            split += step;
    } while (step > 1);
    const int gamma = i + split * d + (d < 0 ? -1 : 0);
    const int first = i < j ? i : j, last = i < j ? j : i;
    return {first == gamma ? ~gamma : gamma, last == gamma + 1 ? ~(gamma + 1) : gamma + 1};
}

// Möller-Trumbore: t of the hit of r with triangle (a, b, c) inside (tnear, tfar), and its
// barycentric coordinates; false on a miss or a ray in the triangle's plane. front: the ray
// struck the side against the counter-clockwise normal.
SDFT_HOST_DEVICE inline bool intersectTriangle(const Ray& r, Vec3 a, Vec3 b, Vec3 c, float tnear,
                                               float tfar, float& t, float& u, float& v,
                                               bool& front) {
    const Vec3 e1 = b - a, e2 = c - a;
    const Vec3 pv = cross(r.direction, e2);
    const float det = dot(e1, pv);
    if (det == 0.0f) return false;
    const float inv = 1.0f / det;
    const Vec3 tv = r.origin - a;
    u = dot(tv, pv) * inv;
    if (u < 0.0f || u > 1.0f) return false;
    const Vec3 qv = cross(tv, e1);
    v = dot(r.direction, qv) * inv;
    if (v < 0.0f || u + v > 1.0f) return false;
    t = dot(e2, qv) * inv;
    if (!(t > tnear && t < tfar)) return false;
    front = det > 0.0f;  // det = -dot(direction, (b - a) x (c - a))
    return true;
}

// The entry t of the ray (origin o, inverse direction inv) into the box, or +inf when it misses
// it within (tnear, tfar).
SDFT_HOST_DEVICE inline float lbvhBoxEntry(Vec3 lo, Vec3 hi, Vec3 o, Vec3 inv, float tnear,
                                           float tfar) {
    float t0 = tnear, t1 = tfar;
    for (int axis = 0; axis < 3; ++axis) {
        float ta = (lo[axis] - o[axis]) * inv[axis], tb = (hi[axis] - o[axis]) * inv[axis];
        t0 = maxf(t0, minf(ta, tb));
        t1 = minf(t1, maxf(ta, tb));
    }
    return t0 <= t1 ? t0 : kInfinity;
}

// The first hit of r(t), tnear < t < tfar, nearer child first; a stack of 64 holds any tree of
// 62-bit keys (its depth is at most their length).
SDFT_HOST_DEVICE inline LbvhHit lbvhFirstHit(const LbvhView& bvh, const Ray& r, float tnear = 0,
                                             float tfar = kInfinity) {
    LbvhHit hit;
    hit.t = tfar;
    auto leaf = [&](int32_t index) {
        const LbvhTriangle& tri = bvh.triangles[index];
        float t, u, v;
        bool front;
        if (intersectTriangle(r, tri.a, tri.b, tri.c, tnear, hit.t, t, u, v, front)) {
            hit.t = t;
            hit.u = u;
            hit.v = v;
            hit.front = front;
            hit.triangle = tri.id;
        }
    };
    if (bvh.count == 1) leaf(0);
    if (bvh.count >= 2) {
        // Zero direction components as tiny ones: their slabs become (-inf, inf) or empty
        // without a 0 * inf.
        Vec3 inv;
        for (int axis = 0; axis < 3; ++axis) {
            const float d = r.direction[axis];
            inv[axis] = 1.0f / (std::fabs(d) > 1e-30f ? d : (d < 0 ? -1e-30f : 1e-30f));
        }
        int32_t stack[64];
        int top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const LbvhNode& node = bvh.nodes[stack[--top]];
            float entry[2] = {kInfinity, kInfinity};
            const int32_t child[2] = {node.left, node.right};
            for (int c = 0; c < 2; ++c) {
                if (child[c] < 0) {
                    leaf(~child[c]);
                } else {
                    const LbvhNode& n = bvh.nodes[child[c]];
                    entry[c] = lbvhBoxEntry(n.lo, n.hi, r.origin, inv, tnear, hit.t);
                }
            }
            // The farther child first on the stack, so the nearer is taken next.
            const int near = entry[1] < entry[0] ? 1 : 0, far = 1 - near;
            if (entry[far] < hit.t && top < 64) stack[top++] = child[far];
            if (entry[near] < hit.t && top < 64) stack[top++] = child[near];
        }
    }
    if (hit.t == tfar) hit = LbvhHit{};
    return hit;
}

// The first hit by testing every triangle of the view in order: the reference the traversal is
// held to (same triangle test, so the same t bit for bit).
SDFT_HOST_DEVICE inline LbvhHit bruteForceFirstHit(const LbvhView& bvh, const Ray& r,
                                                   float tnear = 0, float tfar = kInfinity) {
    LbvhHit hit;
    hit.t = tfar;
    for (int i = 0; i < bvh.count; ++i) {
        const LbvhTriangle& tri = bvh.triangles[i];
        float t, u, v;
        bool front;
        if (intersectTriangle(r, tri.a, tri.b, tri.c, tnear, hit.t, t, u, v, front))
            hit = {t, front, tri.id, u, v};
    }
    if (hit.t == tfar) hit = LbvhHit{};
    return hit;
}

// lbvhFirstHit as a ray caster (castRtsdfRays, rtsdf_vertex.h).
struct LbvhCaster {
    LbvhView bvh;
    SDFT_HOST_DEVICE LbvhHit operator()(const Ray& r, float tnear) const {
        return lbvhFirstHit(bvh, r, tnear);
    }
};

// The LBVH built on the CPU (TBB): keys, sort, internal nodes and bottom-up boxes, the steps the
// GPU build runs as kernels. Owns its arrays; view() lends them.
class Lbvh {
  public:
    // Throws InputError for more than kMaxLbvhTriangles triangles.
    explicit Lbvh(const TriangleMesh& mesh, int threads = 0);

    LbvhView view() const {
        return {m_nodes.data(), m_triangles.data(), static_cast<int>(m_triangles.size())};
    }
    const std::vector<LbvhNode>& nodes() const { return m_nodes; }
    const std::vector<LbvhTriangle>& triangles() const { return m_triangles; }
    int depth() const;  // the longest root-to-leaf path, in nodes

  private:
    std::vector<LbvhNode> m_nodes;
    std::vector<LbvhTriangle> m_triangles;
};

// The box the build's Morton codes quantize over: the mesh's bounds, and 1 / extent per axis (0
// along a flat axis).
struct LbvhFrame {
    Vec3 lo, invExtent;
};
LbvhFrame lbvhFrame(const TriangleMesh& mesh);

}  // namespace sdft
