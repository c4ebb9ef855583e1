// Primary rays on the triangles of meshes (RTSDF's hybrid mode, Tan et al. 2022 §1 and Table 1:
// primary visibility from the triangles, soft shadows and AO marched in the meshes' SDFs). The
// renderer asks this interface for each primary ray's nearest triangle; the scene module
// implements it over Embree (scene/placed_meshes.h), so render stays below bake in the module
// order.
#pragma once

#include <cmath>

#include "sdftrace/math/ray.h"

namespace sdft {

class MeshPrimary {
  public:
    virtual ~MeshPrimary() = default;

    struct Hit {
        float t = INFINITY;  // along the world ray (unit direction)
        Vec3 normal;         // the shading normal, facing the ray's origin
        // World size of a voxel of the mesh's grid: the shading point moves this far off the
        // triangle along the normal before the SDF is asked (RTSDF §2.5.3's bias against
        // self-shadowing).
        float bias = 0;
    };
    // The nearest triangle hit with t < tMax (t = +inf when there is none).
    virtual Hit firstHit(const Ray& ray, float tMax) const = 0;
};

}  // namespace sdft
