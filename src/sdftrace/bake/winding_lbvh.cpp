#include "sdftrace/bake/winding_lbvh.h"

#include <utility>

namespace sdft {

LbvhWinding::LbvhWinding(const LbvhView& lbvh) {
    const int n = lbvh.count;
    if (n == 0) return;
    m_nodes.resize(2 * static_cast<size_t>(n) - 1);
    m_corners.resize(9 * static_cast<size_t>(n));
    for (int j = 0; j < n; ++j) {
        m_nodes[static_cast<size_t>(n - 1 + j)] = windingLeaf(lbvh.triangles[j], j);
        windingCorners(lbvh.triangles[j], m_corners.data() + 9 * static_cast<size_t>(j));
    }
    if (n == 1) return;  // the leaf is the root
    // Post order from the root: a node once both children are done.
    std::vector<std::pair<int, bool>> stack{{0, false}};
    while (!stack.empty()) {
        auto [i, expanded] = stack.back();
        stack.pop_back();
        const LbvhNode& node = lbvh.nodes[i];
        const int l = windingNodeOfLbvhChild(node.left, n),
                  r = windingNodeOfLbvhChild(node.right, n);
        if (expanded) {
            m_nodes[static_cast<size_t>(i)] = windingInner(m_nodes[l], m_nodes[r], l, r);
            continue;
        }
        stack.push_back({i, true});
        if (node.left >= 0) stack.push_back({node.left, false});
        if (node.right >= 0) stack.push_back({node.right, false});
    }
}

}  // namespace sdft
