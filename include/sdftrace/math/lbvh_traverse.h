// The first-hit traversal of a linear BVH over triangles (Karras 2012; built by bake/lbvh.h on
// the CPU and gpu/gpu_lbvh.cu on the GPU) as header functions over plain data: RTSDF's rays in the
// GPU bakes and the triangle primaries of the per-pixel renderer (render/mesh_primary.h) trace
// through it on either device. Plain geometry over rays and triangles, in math so that bake (which
// builds the tree) and render (which traces it) can both include it.
#pragma once

#include <cmath>
#include <cstdint>

#include "sdftrace/core/macros.h"
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

SDFT_HOST_DEVICE inline LbvhHit bruteForceFirstHit(const LbvhView& bvh, const Ray& r,
                                                   float tnear = 0, float tfar = kInfinity);

// The traversal stack's entries: enough for any tree of 62-bit keys (Karras' tree is at most as
// deep as its keys are long). A deeper tree (a view built otherwise) is still answered right: the
// ray whose stack would overflow is answered by testing every triangle, never by dropping
// subtrees.
inline constexpr int kLbvhStack = 64;

// The first hit of r(t), tnear < t < tfar, nearer child first.
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
        int32_t stack[kLbvhStack];
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
            const int pushes = (entry[far] < hit.t) + (entry[near] < hit.t);
            if (top + pushes > kLbvhStack) return bruteForceFirstHit(bvh, r, tnear, tfar);
            if (entry[far] < hit.t) stack[top++] = child[far];
            if (entry[near] < hit.t) stack[top++] = child[near];
        }
    }
    if (hit.t == tfar) hit = LbvhHit{};
    return hit;
}

// The first hit by testing every triangle of the view in order: the reference the traversal is
// held to (same triangle test, so the same t bit for bit).
SDFT_HOST_DEVICE inline LbvhHit bruteForceFirstHit(const LbvhView& bvh, const Ray& r, float tnear,
                                                   float tfar) {
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

}  // namespace sdft
