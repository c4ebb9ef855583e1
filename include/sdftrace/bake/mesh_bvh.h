// A triangle mesh in an Embree BVH: exact closest-point queries (rtcPointQuery) and ray casts for
// inside/outside by crossing parity.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "sdftrace/bake/triangle_mesh.h"

namespace sdft {

class MeshBvh {
  public:
    explicit MeshBvh(const TriangleMesh& mesh);
    ~MeshBvh();
    MeshBvh(const MeshBvh&) = delete;
    MeshBvh& operator=(const MeshBvh&) = delete;

    // Distance from p to the nearest point of the mesh (exact up to float rounding), searching
    // only within `radius`: +infinity when nothing is that close. A tight radius (a neighbour's
    // distance plus their spacing, by the 1-Lipschitz property) prunes most of the traversal.
    float closestDistance(Vec3 p, float radius = INFINITY) const {
        return closest(p, radius).distance;
    }
    struct Closest {
        float distance = INFINITY;
        Vec3 point;
        uint32_t triangle = UINT32_MAX;  // index into mesh().triangles
    };
    // The nearest point itself (distance +infinity when none is within `radius`). A zero-area
    // triangle counts as its longest edge.
    Closest closest(Vec3 p, float radius = INFINITY) const;
    // The first hit of the ray r(t), t > 0: t (+infinity on a miss) and whether it struck the
    // front of the triangle (against its counter-clockwise normal).
    struct Hit {
        float t = INFINITY;
        bool front = false;
        uint32_t triangle = 0;  // index into mesh().triangles
        float u = 0, v = 0;     // barycentric coordinates of the hit: a (1-u-v) + b u + c v
        Vec3 normal;            // (b - a) x (c - a) as Embree computed it, not unit length
    };
    // tnear < 0 also reports hits just behind the origin (origins on the surface); hits beyond
    // tfar are misses. The direction need not be unit length: t is in its units.
    Hit firstHit(const Ray& ray, float tnear = 0, float tfar = INFINITY) const;
    // The change of a closed, consistently oriented mesh's winding number from a to b: +1 for each
    // crossing of the segment against a face's normal, -1 along it. False where a crossing lies
    // within `margin` (barycentric) of a face's edge or within `margin` of the segment's ends in
    // t, or where the segment lies in a face's plane: there a crossing might count twice or not
    // at all.
    bool windingChange(Vec3 a, Vec3 b, int& change, float margin = 1e-4f) const;
    // Surface crossings of the ray r(t), t > 0.
    int crossings(const Ray& ray) const;
    // Inside by crossing parity, the majority of three fixed, non-axis directions (robust to a ray
    // grazing an edge; an open mesh can fool it, which the winding number will not).
    bool insideByParity(Vec3 p) const;

    const TriangleMesh& mesh() const { return m_mesh; }

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
    const TriangleMesh& m_mesh;
};

}  // namespace sdft
