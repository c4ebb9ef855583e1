#include "sdftrace/query/lane_bvh.h"

namespace sdft {

LaneBvh::LaneBvh(const TriangleLanes& lanes) : m_groups(lanes.groups()) {
    // Each group's box, the union of its lanes' boxes: the tree's leaves and the clusters' filter.
    m_boxes.resize(m_groups.size());
    for (size_t i = 0; i < m_groups.size(); ++i) {
        const LaneGroup& g = m_groups[i];
        for (int l = 0; l < kLanes; ++l) {
            m_boxes[i].include(Vec3(g.f[kLox][l], g.f[kLoy][l], g.f[kLoz][l]));
            m_boxes[i].include(Vec3(g.f[kHix][l], g.f[kHiy][l], g.f[kHiz][l]));
        }
    }
    m_tree = std::make_unique<GroupTree>(m_boxes);
}

uint32_t LaneBvh::closest(Vec3 p, float radius, float& d2) const {
    // A group reached: its eight triangles measured at once.
    auto measure = [](const void* context, uint32_t group, Vec3 q, float bound2, uint32_t& id) {
        return nearestInGroups(static_cast<const LaneGroup*>(context) + group, 1, q, bound2, id);
    };
    return m_tree->closest(p, radius * radius, measure, m_groups.data(), d2);
}

bool LaneBvh::near(Vec3 lo, Vec3 hi, float reach, std::vector<uint32_t>& out, size_t limit) const {
    return m_tree->near(lo, hi, reach, out, limit);
}

}  // namespace sdft
