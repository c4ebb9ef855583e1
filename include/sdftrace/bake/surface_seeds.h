// The conservative voxelization the propagation bakes (jump flooding, Danielsson, the separable
// EDT, RTSDF's coarse field) start from: every grid vertex within half a cell diagonal of a
// triangle holds its closest point on the nearest such triangle (RTSDF §2.2: "check if a grid
// point contains a model voxel to determine if it is a seed").
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "sdftrace/bake/jump_flood_step.h"
#include "sdftrace/bake/triangle_mesh.h"
#include "sdftrace/field/grid.h"

namespace sdft {

struct SurfaceSeeds {
    std::vector<Vec3> point;         // per vertex (x fastest); kNoSeed in x: not a seed
    std::vector<uint32_t> triangle;  // the triangle the point lies on
};

// The vertices of `shape` inside the bounds of triangle (a, b, c) grown by `grow` (clamped to the
// grid; empty when lo > hi on some axis). Every vertex within `grow` of the triangle is inside.
struct VertexRange {
    int lo[3], hi[3];
    SDFT_HOST_DEVICE bool empty() const { return lo[0] > hi[0] || lo[1] > hi[1] || lo[2] > hi[2]; }
};
SDFT_HOST_DEVICE inline VertexRange triangleVertexRange(const GridShape& s, Vec3 a, Vec3 b, Vec3 c,
                                                        float grow) {
    const Vec3 lo = (min(a, min(b, c)) - s.origin - Vec3(grow)) / s.voxelSize;
    const Vec3 hi = (max(a, max(b, c)) - s.origin + Vec3(grow)) / s.voxelSize;
    VertexRange r;
    for (int axis = 0; axis < 3; ++axis) {
        const int l = static_cast<int>(ceilf(lo[axis])), h = static_cast<int>(floorf(hi[axis]));
        r.lo[axis] = l > 0 ? l : 0;
        r.hi[axis] = h < s.vertices(axis) - 1 ? h : s.vertices(axis) - 1;
    }
    return r;
}

// How near a triangle a vertex must be to be a seed: half a cell diagonal, rounded up.
SDFT_HOST_DEVICE inline float seedReach(const GridShape& s) { return 0.87f * s.voxelSize; }

// In parallel over slabs of z layers, each visiting the triangles that overlap it in index order,
// so the result is the same for any thread count.
SurfaceSeeds seedSurfaceVertices(const TriangleMesh& mesh, const GridShape& shape, int threads = 0);

// The distance from every vertex to its propagated closest point (kNoSeed where none arrived).
std::vector<float> distancesToPoints(const GridShape& shape, const std::vector<Vec3>& points,
                                     int threads = 0);

}  // namespace sdft
