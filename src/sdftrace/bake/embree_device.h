// The process's one Embree device (defined in mesh_bvh.cpp), for every scene sdftrace builds, and
// the point queries they answer.
#pragma once

#include <embree3/rtcore.h>

#include "sdftrace/math/vec.h"

namespace sdft {

// Started on first use; throws InputError where Embree cannot start.
RTCDevice embreeDevice();

// A point query: the sphere of `radius` about p.
inline RTCPointQuery pointQueryAt(Vec3 p, float radius) {
    RTCPointQuery q;
    q.x = p.x;
    q.y = p.y;
    q.z = p.z;
    q.time = 0;
    q.radius = radius;
    return q;
}

}  // namespace sdft
