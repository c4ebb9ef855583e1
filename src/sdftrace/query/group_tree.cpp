#include "sdftrace/query/group_tree.h"

#include <cmath>

#include "sdftrace/core/macros.h"
#include "sdftrace/exec/simd.h"
#include "sdftrace/query/lane_vectors.h"

namespace sdft {

GroupTree::GroupTree(const std::vector<Bounds3>& boxes) : m_groups(boxes.size()) {
    // Level 0 from the groups, then each level from the one below until one node is left.
    auto empty = [] {
        Node n;
        for (int a = 0; a < 3; ++a)
            for (int l = 0; l < 8; ++l) {
                n.lo[a][l] = INFINITY;
                n.hi[a][l] = -INFINITY;
            }
        return n;
    };
    std::vector<Bounds3> below = boxes;
    do {
        std::vector<Node> level((below.size() + 7) / 8, empty());
        std::vector<Bounds3> above(level.size());
        for (size_t i = 0; i < below.size(); ++i) {
            Node& n = level[i / 8];
            const Bounds3& b = below[i];
            for (int a = 0; a < 3; ++a) {
                n.lo[a][i % 8] = b.lo[a];
                n.hi[a][i % 8] = b.hi[a];
            }
            above[i / 8].include(b.lo);
            above[i / 8].include(b.hi);
        }
        m_levels.push_back(std::move(level));
        below = std::move(above);
    } while (below.size() > 1);
}

namespace {

using namespace lane_vectors;

// The squared gaps between a node's eight boxes and the box [qlo, qhi].
__attribute__((always_inline)) inline Floats nodeGap2(const GroupTree::Node& n, const Floats qlo[3],
                                                      const Floats qhi[3]) {
    const Floats lo[3] = {load(n.lo[0]), load(n.lo[1]), load(n.lo[2])};
    const Floats hi[3] = {load(n.hi[0]), load(n.hi[1]), load(n.hi[2])};
    return gapSquared(lo, hi, qlo, qhi);
}

// The depth-first walk: a node's children that reach the query box are visited in increasing
// order (pushed in decreasing order), so the groups come out in increasing order.
template <bool kAvx2>
__attribute__((always_inline)) inline bool nearBody(
    const std::vector<std::vector<GroupTree::Node>>& levels, size_t groups, Vec3 lo, Vec3 hi,
    float reach, std::vector<uint32_t>& out, size_t limit) {
    const size_t before = out.size();
    const Floats zero = {}, reach2 = zero + reach * reach;
    const Floats qlo[3] = {zero + lo.x, zero + lo.y, zero + lo.z};
    const Floats qhi[3] = {zero + hi.x, zero + hi.y, zero + hi.z};
    struct Entry {
        uint32_t level, node;
    };
    Entry stack[8 * 32];  // at most 7 pending a level, 32 levels
    int top = 0;
    stack[top++] = {static_cast<uint32_t>(levels.size() - 1), 0};
    while (top > 0) {
        const Entry e = stack[--top];
        // An empty box's gap is +inf (or NaN against an infinite query): never within reach.
        unsigned bits = laneBits<kAvx2>(nodeGap2(levels[e.level][e.node], qlo, qhi) <= reach2);
        if (e.level == 0) {
            for (; bits; bits &= bits - 1) {
                const size_t g = e.node * size_t{8} + static_cast<size_t>(__builtin_ctz(bits));
                if (g >= groups) break;
                out.push_back(static_cast<uint32_t>(g));
                if (out.size() - before > limit) return false;
            }
            continue;
        }
        const size_t children = levels[e.level - 1].size();
        for (; bits; bits &= ~(1u << (31 - __builtin_clz(bits)))) {
            const uint32_t c = e.node * 8 + static_cast<uint32_t>(31 - __builtin_clz(bits));
            if (c < children) stack[top++] = {e.level - 1, c};  // (an infinite reach meets all)
        }
    }
    return true;
}

// A node's children within the bound, nearest first (insertion sort of at most eight).
struct Child {
    float gap2;
    uint32_t index;
};
template <bool kAvx2>
__attribute__((always_inline)) inline int reachingChildren(const GroupTree::Node& n, Vec3 p,
                                                           float bound2, size_t children,
                                                           uint32_t first, Child out[8]) {
    const Floats zero = {};
    const Floats q[3] = {zero + p.x, zero + p.y, zero + p.z};
    const Floats gap2 = nodeGap2(n, q, q);
    int count = 0;
    for (unsigned bits = laneBits<kAvx2>(gap2 <= bound2); bits; bits &= bits - 1) {
        const int l = __builtin_ctz(bits);
        const uint32_t c = first + static_cast<uint32_t>(l);
        if (c >= children) break;
        int k = count++;
        for (; k > 0 && out[k - 1].gap2 > gap2[l]; --k) out[k] = out[k - 1];
        out[k] = {gap2[l], c};
    }
    return count;
}

template <bool kAvx2>
__attribute__((always_inline)) inline uint32_t closestBody(
    const std::vector<std::vector<GroupTree::Node>>& levels, size_t groups, Vec3 p, float bound2,
    GroupTree::Measure measure, const void* context, float& d2) {
    struct Entry {
        uint32_t level, node;
        float gap2;
    };
    Entry stack[8 * 32];
    int top = 0;
    stack[top++] = {static_cast<uint32_t>(levels.size() - 1), 0, 0.0f};
    float best2 = bound2;
    uint32_t best = UINT32_MAX;
    while (top > 0) {
        const Entry e = stack[--top];
        if (e.gap2 > best2) continue;
        const size_t children = e.level == 0 ? groups : levels[e.level - 1].size();
        Child c[8];
        const int count =
            reachingChildren<kAvx2>(levels[e.level][e.node], p, best2, children, e.node * 8, c);
        if (e.level > 0) {
            for (int k = count - 1; k >= 0; --k)
                stack[top++] = {e.level - 1, c[k].index, c[k].gap2};
            continue;
        }
        for (int k = 0; k < count && c[k].gap2 <= best2; ++k) {
            uint32_t id = UINT32_MAX;
            const float g2 = measure(context, c[k].index, p, best2, id);
            if (id != UINT32_MAX && g2 <= best2 && (best == UINT32_MAX || g2 < best2)) {
                best2 = g2;
                best = id;
            }
        }
    }
    d2 = best == UINT32_MAX ? INFINITY : best2;
    return best;
}

SDFT_TARGET_AVX2 uint32_t closestAvx2(const std::vector<std::vector<GroupTree::Node>>& levels,
                                      size_t groups, Vec3 p, float bound2,
                                      GroupTree::Measure measure, const void* context, float& d2) {
    return closestBody<true>(levels, groups, p, bound2, measure, context, d2);
}
SDFT_TARGET_BASELINE uint32_t
closestBaseline(const std::vector<std::vector<GroupTree::Node>>& levels, size_t groups, Vec3 p,
                float bound2, GroupTree::Measure measure, const void* context, float& d2) {
    return closestBody<false>(levels, groups, p, bound2, measure, context, d2);
}

SDFT_TARGET_AVX2 bool nearAvx2(const std::vector<std::vector<GroupTree::Node>>& levels,
                               size_t groups, Vec3 lo, Vec3 hi, float reach,
                               std::vector<uint32_t>& out, size_t limit) {
    return nearBody<true>(levels, groups, lo, hi, reach, out, limit);
}
SDFT_TARGET_BASELINE bool nearBaseline(const std::vector<std::vector<GroupTree::Node>>& levels,
                                       size_t groups, Vec3 lo, Vec3 hi, float reach,
                                       std::vector<uint32_t>& out, size_t limit) {
    return nearBody<false>(levels, groups, lo, hi, reach, out, limit);
}

}  // namespace

bool GroupTree::near(Vec3 lo, Vec3 hi, float reach, std::vector<uint32_t>& out,
                     size_t limit) const {
    if (m_groups == 0) return true;
    return useAvx2() ? nearAvx2(m_levels, m_groups, lo, hi, reach, out, limit)
                     : nearBaseline(m_levels, m_groups, lo, hi, reach, out, limit);
}

uint32_t GroupTree::closest(Vec3 p, float bound2, Measure measure, const void* context,
                            float& d2) const {
    d2 = INFINITY;
    if (m_groups == 0) return UINT32_MAX;
    return useAvx2() ? closestAvx2(m_levels, m_groups, p, bound2, measure, context, d2)
                     : closestBaseline(m_levels, m_groups, p, bound2, measure, context, d2);
}

}  // namespace sdft
