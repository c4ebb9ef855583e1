// A triangle mesh in an Embree BVH: exact closest-point queries (rtcPointQuery) and ray casts for
// inside/outside by crossing parity.
#pragma once

#include <memory>

#include "sdftrace/io/mesh_io.h"

namespace sdft {

class MeshBvh {
  public:
    explicit MeshBvh(const TriangleMesh& mesh);
    ~MeshBvh();
    MeshBvh(const MeshBvh&) = delete;
    MeshBvh& operator=(const MeshBvh&) = delete;

    // Distance from p to the nearest point of the mesh (exact up to float rounding).
    float closestDistance(Vec3 p) const;
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
