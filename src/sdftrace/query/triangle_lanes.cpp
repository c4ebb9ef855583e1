#include "sdftrace/query/triangle_lanes.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "sdftrace/bake/lbvh.h"
#include "sdftrace/core/macros.h"
#include "sdftrace/exec/simd.h"
#include "sdftrace/query/lane_vectors.h"

namespace sdft {

TriangleLanes::TriangleLanes(const TriangleMesh& mesh) {
    // Eight neighbours to a group: sorted by the LBVH's keys (Morton code above index).
    const size_t n = mesh.triangles.size();
    const LbvhFrame frame = lbvhFrame(mesh);
    std::vector<uint64_t> keys(n);
    tbb::parallel_for(size_t{0}, n, [&](size_t i) {
        const auto& t = mesh.triangles[i];
        keys[i] = lbvhKey(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]],
                          frame.lo, frame.invExtent, static_cast<uint32_t>(i));
    });
    tbb::parallel_sort(keys.begin(), keys.end());
    m_groups.resize((n + kLanes - 1) / kLanes);
    m_place.resize(n);
    tbb::parallel_for(size_t{0}, m_groups.size() * kLanes, [&](size_t k) {
        // A short last group repeats its first triangle.
        const auto i = static_cast<uint32_t>(keys[k < n ? k : k - k % kLanes]);
        if (k < n) m_place[i] = static_cast<uint32_t>(k);
        const auto& t = mesh.triangles[i];
        const Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
        const Vec3 ab = b - a, ac = c - a, bc = c - b;
        const Vec3 lo = min(a, min(b, c)), hi = max(a, max(b, c));
        // In double: the Gram determinant cancels badly in float for slivers.
        auto dotd = [](Vec3 u, Vec3 v) {
            return double{u.x} * v.x + double{u.y} * v.y + double{u.z} * v.z;
        };
        const double d00 = dotd(ab, ab), d01 = dotd(ab, ac), d11 = dotd(ac, ac);
        const double det = d00 * d11 - d01 * d01;
        const bool face = det > 1e-12 * d00 * d11;
        auto inv = [](double x) { return x > 0 ? static_cast<float>(1 / x) : 0.0f; };
        auto weight = [&](double x) { return face ? static_cast<float>(x / det) : 0.0f; };
        // clang-format off
        const float r[kFields] = {
            a.x, a.y, a.z, ab.x, ab.y, ab.z, ac.x, ac.y, ac.z, bc.x, bc.y, bc.z,
            weight(d11), weight(d01), weight(d00),
            inv(d00), inv(d11), inv(dotd(bc, bc)), face ? 1.0f : -1.0f,
            lo.x, lo.y, lo.z, hi.x, hi.y, hi.z};
        // clang-format on
        LaneGroup& g = m_groups[k / kLanes];
        g.id[k % kLanes] = i;
        for (int f = 0; f < kFields; ++f) g.f[f][k % kLanes] = r[f];
    });
}

namespace {

using namespace lane_vectors;

// groupsWithinBounds, eight points to a vector.
template <bool kAvx2>
__attribute__((always_inline)) inline void withinBody(const Bounds3* boxes, const uint32_t* which,
                                                      size_t count, const Vec3* p,
                                                      const float* bound2, size_t n, uint32_t* out,
                                                      uint32_t* outCount) {
    for (size_t i = 0; i < n; ++i) outCount[i] = 0;
    for (size_t first = 0; first < n; first += kLanes) {
        const size_t m = n - first < kLanes ? n - first : kLanes;
        Floats q[3] = {}, b2 = {};
        for (size_t l = 0; l < m; ++l) {
            for (int a = 0; a < 3; ++a) q[a][l] = p[first + l][a];
            b2[l] = bound2[first + l];
        }
        const Floats zero = {};
        const Ints valid = (Ints{0, 1, 2, 3, 4, 5, 6, 7} < static_cast<int>(m));
        for (size_t g = 0; g < count; ++g) {
            const Bounds3& box = boxes[which[g]];
            const Floats lo[3] = {zero + box.lo.x, zero + box.lo.y, zero + box.lo.z};
            const Floats hi[3] = {zero + box.hi.x, zero + box.hi.y, zero + box.hi.z};
            for (unsigned bits = laneBits<kAvx2>(valid & (gapSquared(lo, hi, q, q) <= b2)); bits;
                 bits &= bits - 1) {
                const size_t i = first + static_cast<size_t>(__builtin_ctz(bits));
                out[i * count + outCount[i]++] = which[g];
            }
        }
    }
}

// Point-triangle distance without branches (after Ericson, Real-Time Collision Detection
// §5.1.5): the projection onto the plane where its barycentric weights are inside the face, else
// the nearest of the three edges, each lane computing all four.
template <bool kAvx2, class GroupAt>
__attribute__((always_inline)) inline float nearestBody(GroupAt groupAt, size_t count, Vec3 p,
                                                        float bound2, uint32_t& id) {
    const Floats zero = {}, one = zero + 1.0f, px = zero + p.x, py = zero + p.y, pz = zero + p.z;
    Floats best = zero + INFINITY;
    Ints slot = {};
    for (size_t g = 0; g < count; ++g) {
        const auto& f = groupAt(g).f;
        // gapSquared (lane_vectors.h) written out: through its arrays this loop took 1.4 % more
        // instructions (callgrind, the thin part's 1M points).
        const Floats gx = vmax(vmax(load(f[kLox]) - px, px - load(f[kHix])), zero);
        const Floats gy = vmax(vmax(load(f[kLoy]) - py, py - load(f[kHiy])), zero);
        const Floats gz = vmax(vmax(load(f[kLoz]) - pz, pz - load(f[kHiz])), zero);
        if (laneBits<kAvx2>(gx * gx + gy * gy + gz * gz <= bound2) == 0) continue;
        const Floats apx = px - load(f[kAx]), apy = py - load(f[kAy]), apz = pz - load(f[kAz]);
        const Floats abx = load(f[kAbx]), aby = load(f[kAby]), abz = load(f[kAbz]);
        const Floats acx = load(f[kAcx]), acy = load(f[kAcy]), acz = load(f[kAcz]);
        const Floats d20 = apx * abx + apy * aby + apz * abz;
        const Floats d21 = apx * acx + apy * acy + apz * acz;
        const Floats s = load(f[kS20]) * d20 - load(f[kS21]) * d21;
        const Floats t = load(f[kT21]) * d21 - load(f[kS21]) * d20;
        // The projection as a point of the face (not the plane's distance): never nearer than
        // the face itself, however a sliver's weights round.
        const Floats fx = apx - s * abx - t * acx, fy = apy - s * aby - t * acy,
                     fz = apz - s * abz - t * acz;
        const Floats faceD2 = fx * fx + fy * fy + fz * fz;
        const Ints inside = (s >= zero) & (t >= zero) & (s + t <= load(f[kFaceLimit]));
        // Edge ab.
        const Floats u0 = vmin(vmax(d20 * load(f[kInvAb]), zero), one);
        const Floats q0x = apx - u0 * abx, q0y = apy - u0 * aby, q0z = apz - u0 * abz;
        const Floats e0 = q0x * q0x + q0y * q0y + q0z * q0z;
        // Edge ac.
        const Floats u1 = vmin(vmax(d21 * load(f[kInvAc]), zero), one);
        const Floats q1x = apx - u1 * acx, q1y = apy - u1 * acy, q1z = apz - u1 * acz;
        const Floats e1 = q1x * q1x + q1y * q1y + q1z * q1z;
        // Edge bc.
        const Floats bpx = apx - abx, bpy = apy - aby, bpz = apz - abz;
        const Floats bcx = load(f[kBcx]), bcy = load(f[kBcy]), bcz = load(f[kBcz]);
        const Floats u2 =
            vmin(vmax((bpx * bcx + bpy * bcy + bpz * bcz) * load(f[kInvBc]), zero), one);
        const Floats q2x = bpx - u2 * bcx, q2y = bpy - u2 * bcy, q2z = bpz - u2 * bcz;
        const Floats e2 = q2x * q2x + q2y * q2y + q2z * q2z;
        const Floats edges = vmin(vmin(e0, e1), e2);
        const Floats d2 = inside ? vmin(faceD2, edges) : edges;
        const Ints better = d2 < best;
        best = better ? d2 : best;
        slot = better ? static_cast<int>(g) + Ints{} : slot;
    }
    int lane = 0;
    for (int l = 1; l < kLanes; ++l)
        if (best[l] < best[lane]) lane = l;
    if (best[lane] < INFINITY) id = groupAt(static_cast<size_t>(slot[lane])).id[lane];
    return best[lane];
}

// The groups in an array, or those an index list names in it.
struct Contiguous {
    const LaneGroup* groups;
    const LaneGroup& operator()(size_t g) const { return groups[g]; }
};
struct Listed {
    const LaneGroup* groups;
    const uint32_t* which;
    const LaneGroup& operator()(size_t g) const { return groups[which[g]]; }
};

SDFT_TARGET_AVX2 void withinAvx2(const Bounds3* boxes, const uint32_t* which, size_t count,
                                 const Vec3* p, const float* bound2, size_t n, uint32_t* out,
                                 uint32_t* outCount) {
    withinBody<true>(boxes, which, count, p, bound2, n, out, outCount);
}
SDFT_TARGET_BASELINE void withinBaseline(const Bounds3* boxes, const uint32_t* which, size_t count,
                                         const Vec3* p, const float* bound2, size_t n,
                                         uint32_t* out, uint32_t* outCount) {
    withinBody<false>(boxes, which, count, p, bound2, n, out, outCount);
}

template <class GroupAt>
SDFT_TARGET_AVX2 float nearestAvx2(GroupAt at, size_t count, Vec3 p, float bound2, uint32_t& id) {
    return nearestBody<true>(at, count, p, bound2, id);
}
template <class GroupAt>
SDFT_TARGET_BASELINE float nearestBaseline(GroupAt at, size_t count, Vec3 p, float bound2,
                                           uint32_t& id) {
    return nearestBody<false>(at, count, p, bound2, id);
}

}  // namespace

float nearestInGroups(const LaneGroup* groups, size_t count, Vec3 p, float bound2, uint32_t& id) {
    // The project's run-time dispatch (exec/simd.h): both levels round alike (no FMA).
    const Contiguous at{groups};
    return useAvx2() ? nearestAvx2(at, count, p, bound2, id)
                     : nearestBaseline(at, count, p, bound2, id);
}

float nearestInGroupList(const LaneGroup* groups, const uint32_t* which, size_t count, Vec3 p,
                         float bound2, uint32_t& id) {
    const Listed at{groups, which};
    return useAvx2() ? nearestAvx2(at, count, p, bound2, id)
                     : nearestBaseline(at, count, p, bound2, id);
}

void groupsWithinBounds(const Bounds3* boxes, const uint32_t* which, size_t count, const Vec3* p,
                        const float* bound2, size_t n, uint32_t* out, uint32_t* outCount) {
    if (useAvx2())
        withinAvx2(boxes, which, count, p, bound2, n, out, outCount);
    else
        withinBaseline(boxes, which, count, p, bound2, n, out, outCount);
}

}  // namespace sdft
