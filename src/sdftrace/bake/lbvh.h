// A linear BVH over a triangle mesh (Karras 2012, "Maximizing Parallelism in the Construction of
// BVHs, Octrees, and k-d Trees", §3-4): the triangles sorted by the 30-bit Morton code of their
// centroid (the index below it makes every key unique), the binary radix tree over the sorted keys
// built one internal node per thread, and the boxes filled bottom-up, each node by the second of
// its children to finish. Every step is a header function run per element: by TBB on the CPU
// (Lbvh, bake/lbvh.cpp) and by one CUDA thread per element on the GPU (gpu/gpu_lbvh.cu); the
// first-hit traversal (math/lbvh_traverse.h) is the same function on both. Why an LBVH and not a
// SAH tree: docs/decisions/0013-lbvh-for-gpu-rays.md.
#pragma once

#include <cstdint>
#include <vector>

#include "sdftrace/bake/triangle_mesh.h"
#include "sdftrace/math/lbvh_traverse.h"
#include "sdftrace/math/ray.h"

namespace sdft {

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
