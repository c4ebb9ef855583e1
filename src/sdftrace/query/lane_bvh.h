// The BVH over lane groups (triangle_lanes.h): a point's nearest triangle found eight triangles
// at a time. The groups are eight Morton neighbours each, and the tree over them is implicit
// (group_tree.h: eight consecutive groups to a node, a node's eight boxes tested in one vector
// test). Over single triangles a far point of a fine mesh paid some 90 visits and 50 scalar
// point-triangle tests in Embree's point query (its sphere meets that many faces within their
// boxes' slack, however tight the bound); over groups it pays a few vectorized tests of eight.
// Embree's point query over the groups as user primitives took as long for single points and
// several times the instructions for a cluster's box query (its sphere about the box lets in
// more groups, and it calls back once for each).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "sdftrace/math/ray.h"
#include "sdftrace/query/group_tree.h"
#include "sdftrace/query/triangle_lanes.h"

namespace sdft {

class LaneBvh {
  public:
    // Over lanes.groups(), which must outlive this.
    explicit LaneBvh(const TriangleLanes& lanes);

    // The triangle nearest p within `radius` (UINT32_MAX where none is) and its squared distance
    // by the float lane test.
    uint32_t closest(Vec3 p, float radius, float& d2) const;
    // The groups whose boxes come within `reach` of the box [lo, hi], appended to `out` in
    // increasing order: false (the search cut short) where they are more than `limit`.
    bool near(Vec3 lo, Vec3 hi, float reach, std::vector<uint32_t>& out, size_t limit) const;
    // Each group's box, the union of its lanes' boxes.
    const std::vector<Bounds3>& boxes() const { return m_boxes; }

  private:
    const std::vector<LaneGroup>& m_groups;
    std::vector<Bounds3> m_boxes;  // per group
    std::unique_ptr<GroupTree> m_tree;
};

}  // namespace sdft
