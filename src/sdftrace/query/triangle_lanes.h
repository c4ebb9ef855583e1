// Triangles eight to a lane group for batched point-triangle distances: each group eight Morton
// neighbours, found by one BVH traversal (lane_bvh.h) for a point or for a cluster of nearby
// points (neighbours in Morton order), and each point then measures a group's triangles at once
// with a branch-free test that the compiler vectorizes eight wide (AVX2 where the CPU has it, SSE
// otherwise: exec/simd.h's choice).
// The test is float, as the BVH search it replaces; MeshQuery refines the winner in double.
#pragma once

#include <cstdint>
#include <vector>

#include "sdftrace/bake/triangle_mesh.h"
#include "sdftrace/math/ray.h"

namespace sdft {

inline constexpr int kLanes = 8;

// One triangle's precomputed terms, in the order a lane group stores them.
// clang-format off
enum TriangleField : int {
    kAx, kAy, kAz,              // corner a
    kAbx, kAby, kAbz,           // b - a
    kAcx, kAcy, kAcz,           // c - a
    kBcx, kBcy, kBcz,           // c - b
    kS20, kS21,                 // s = S20 (ap.ab) - S21 (ap.ac): the projection's weight of b
    kT21,                       // t = T21 (ap.ac) - S21 (ap.ab): of c
    kInvAb, kInvAc, kInvBc,     // 1 / |edge|^2 (0: zero length)
    kFaceLimit,                 // inside the face: s + t <= limit, 1 (-1: no area)
    kLox, kLoy, kLoz, kHix, kHiy, kHiz,  // bounding box
    kFields
};
// clang-format on

struct alignas(32) LaneGroup {
    float f[kFields][kLanes];
    uint32_t id[kLanes];  // the triangles' indices (a short last group repeats its first)
};

class TriangleLanes {
  public:
    explicit TriangleLanes(const TriangleMesh& mesh);

    // Every triangle in groups of eight neighbours (in the Morton order of their centroids, a
    // short last group repeating its first): the leaves of LaneBvh (lane_bvh.h).
    const std::vector<LaneGroup>& groups() const { return m_groups; }
    uint32_t groupOf(uint32_t triangle) const { return m_place[triangle] / kLanes; }

  private:
    std::vector<LaneGroup> m_groups;
    std::vector<uint32_t> m_place;  // per triangle, its group times kLanes plus its lane
};

// The least squared distance from p to the triangles of `groups` (count > 0), skipping a group
// whose every box lies farther than sqrt(bound2), and that triangle's id in `id`: +infinity (id
// untouched) when every group was skipped.
float nearestInGroups(const LaneGroup* groups, size_t count, Vec3 p, float bound2, uint32_t& id);
// The same over the `count` groups of `groups` that `which` names.
float nearestInGroupList(const LaneGroup* groups, const uint32_t* which, size_t count, Vec3 p,
                         float bound2, uint32_t& id);

// For n points p[i] with squared bounds bound2[i]: the groups of `which` (count of them, boxes
// indexed by group) whose box comes within each point's bound, in which's order. Point i's are
// out[i * count ...], outCount[i] of them. The points are tested eight at a time against one
// group's box, so a cluster pays one box test per group and eight points, not per point.
void groupsWithinBounds(const Bounds3* boxes, const uint32_t* which, size_t count, const Vec3* p,
                        const float* bound2, size_t n, uint32_t* out, uint32_t* outCount);

}  // namespace sdft
