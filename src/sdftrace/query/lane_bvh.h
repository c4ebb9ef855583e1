// Embree's BVH over lane groups (triangle_lanes.h): a point's nearest triangle found eight
// triangles at a time. Embree's point query calls its user function once per primitive its
// traversal reaches; with triangles as the primitives a far point of a fine mesh pays some 90
// calls and 50 scalar point-triangle tests (its sphere meets that many faces within their boxes'
// slack, however tight the bound), with groups of eight Morton neighbours as the primitives it
// pays a few calls, each one vectorized test of eight.
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>

#include "sdftrace/math/ray.h"
#include "sdftrace/query/triangle_lanes.h"

namespace sdft {

class LaneBvh {
  public:
    // Over lanes.groups(), which must outlive this.
    explicit LaneBvh(const TriangleLanes& lanes);
    ~LaneBvh();
    LaneBvh(const LaneBvh&) = delete;
    LaneBvh& operator=(const LaneBvh&) = delete;

    // The triangle nearest p within `radius` (UINT32_MAX where none is) and its squared distance
    // by the float lane test.
    uint32_t closest(Vec3 p, float radius, float& d2) const;
    // The groups whose boxes come within `reach` of the box [lo, hi], appended to `out`: false
    // (the search cut short) where they are more than `limit`.
    bool near(Vec3 lo, Vec3 hi, float reach, std::vector<uint32_t>& out, size_t limit) const;
    // Each group's box, the union of its lanes' boxes.
    const std::vector<Bounds3>& boxes() const { return m_boxes; }

  private:
    const std::vector<LaneGroup>& m_groups;
    std::vector<Bounds3> m_boxes;  // per group
    RTCScene m_scene = nullptr;
};

}  // namespace sdft
