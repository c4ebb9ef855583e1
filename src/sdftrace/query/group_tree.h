// The lane groups' boxes (triangle_lanes.h) in an implicit eight-ary tree: the groups are in the
// Morton order of their triangles, so eight consecutive groups are neighbours, and a node is the
// box of eight consecutive children, the levels stored whole, each node's eight child boxes side
// by side (one vector of each coordinate). A query tests a node's eight children in one vector
// test and descends where they reach: the groups within a reach of a box (a cluster's
// candidates, by the exact gap between boxes), or a point's nearest (nearest boxes first, the
// bound shrinking to each find). No pointers, no per-primitive callbacks.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "sdftrace/math/ray.h"

namespace sdft {

class GroupTree {
  public:
    // Over per-group boxes, in the groups' order.
    explicit GroupTree(const std::vector<Bounds3>& boxes);

    // The groups whose boxes come within `reach` of the box [lo, hi] (by the gap between the two
    // boxes), appended to `out` in increasing order: false, the search cut short, where they are
    // more than `limit`.
    bool near(Vec3 lo, Vec3 hi, float reach, std::vector<uint32_t>& out, size_t limit) const;

    // What a group holds nearest p within sqrt(bound2): its squared distance (+infinity or more
    // than bound2 where nothing is within) and the id of what it found.
    using Measure = float (*)(const void* context, uint32_t group, Vec3 p, float bound2,
                              uint32_t& id);
    // The nearest of what `measure` finds in the groups whose boxes come within sqrt(bound2) of
    // p, visiting the nearest boxes first and shrinking the bound to each find: its id
    // (UINT32_MAX where none is within) and squared distance in d2.
    uint32_t closest(Vec3 p, float bound2, Measure measure, const void* context, float& d2) const;

    // Eight boxes, each coordinate of the eight side by side; an absent one is empty (lo = +inf,
    // hi = -inf), which reaches nothing.
    struct alignas(32) Node {
        float lo[3][8], hi[3][8];
    };
    // Level 0 holds the groups' boxes (node j: groups 8j..8j+7); level k + 1 node j holds the
    // boxes of level k's nodes 8j..8j+7. The last level has one node.
    const std::vector<std::vector<Node>>& levels() const { return m_levels; }

  private:
    std::vector<std::vector<Node>> m_levels;
    size_t m_groups = 0;
};

}  // namespace sdft
