// Primary rays on the triangles of meshes (RTSDF's hybrid mode, Tan et al. 2022 §1 and Table 1:
// primary visibility from the triangles, soft shadows and AO marched in the meshes' SDFs). The
// CPU renderer asks the MeshPrimary interface for each primary ray's nearest triangle; the scene
// module implements it over Embree (scene/placed_meshes.h), so render stays below bake in the
// module order. The per-pixel path (render/primary_pixel.h, a GPU thread) traces the same meshes
// through their LBVHs (math/lbvh_traverse.h) as plain data: MeshPrimaryView.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "sdftrace/core/macros.h"
#include "sdftrace/field/device_resident_grid.h"
#include "sdftrace/math/lbvh_traverse.h"
#include "sdftrace/math/ray.h"
#include "sdftrace/math/vec.h"

namespace sdft {

// A triangle hit of a primary ray.
struct MeshPrimaryHit {
    float t = INFINITY;  // along the world ray (unit direction)
    Vec3 normal;         // the shading normal, facing the ray's origin
    // World size of a voxel of the mesh's grid: the shading point moves this far off the
    // triangle along the normal before the SDF is asked (RTSDF §2.5.3's bias against
    // self-shadowing).
    float bias = 0;
};

// An affine map x -> linear x + offset.
struct Affine {
    Mat3 linear;
    Vec3 offset{0, 0, 0};
    SDFT_HOST_DEVICE Vec3 point(Vec3 x) const { return linear * x + offset; }
};

// One placed mesh as the per-pixel path reads it (host or device memory).
struct MeshPrimaryMesh {
    LbvhView bvh;                       // in the mesh's coordinates
    const Vec3* normals = nullptr;      // per vertex, mesh coordinates (area-weighted)
    const uint32_t* indices = nullptr;  // 3 per triangle: its vertices
    Affine toLocal;                     // world to mesh
    Mat3 normalToWorld;                 // the inverse transpose of mesh-to-world's linear part
    float bias = 0;                     // MeshPrimaryHit::bias
};

struct MeshPrimaryView {
    const MeshPrimaryMesh* meshes = nullptr;
    int count = 0;
};

// The nearest triangle hit with t < tMax over the meshes (t = +inf when there is none): what
// PlacedMeshes::firstHit answers through Embree, here through each mesh's LBVH. The ray is carried
// into the mesh's coordinates with its direction not renormalised, so t stays the world distance.
SDFT_HOST_DEVICE inline MeshPrimaryHit meshPrimaryHit(const MeshPrimaryView& v, const Ray& ray,
                                                      float tMax) {
    MeshPrimaryHit best;
    best.t = tMax;
    for (int i = 0; i < v.count; ++i) {
        const MeshPrimaryMesh& m = v.meshes[i];
        const Vec3 o = m.toLocal.point(ray.origin);
        const Vec3 d = m.toLocal.linear * ray.direction;
        const LbvhHit h = lbvhFirstHit(m.bvh, Ray{o, d}, 0.0f, best.t);
        if (!(h.t < best.t)) continue;
        const uint32_t* tri = m.indices + 3 * static_cast<size_t>(h.triangle);
        const Vec3 local =
            m.normals[tri[0]] * (1 - h.u - h.v) + m.normals[tri[1]] * h.u + m.normals[tri[2]] * h.v;
        Vec3 n = normalize(m.normalToWorld * (length(local) > 0 ? local : Vec3(0, 1, 0)));
        if (dot(n, ray.direction) > 0) n = -n;
        best = {h.t, n, m.bias};
    }
    if (!(best.t < tMax)) best.t = INFINITY;
    return best;
}

// The host arrays a MeshPrimaryView points into: each mesh's LBVH, normals and indices.
struct MeshPrimaryTables {
    struct Mesh {
        std::vector<LbvhNode> nodes;
        std::vector<LbvhTriangle> triangles;
        std::vector<Vec3> normals;
        std::vector<uint32_t> indices;
        Affine toLocal;
        Mat3 normalToWorld;
        float bias = 0;
        // A mesh posed on the GPU (an RTSDF mesh whose grid lives there, DeviceResidentGrid):
        // the arrays above are empty and a GPU renderer reads the baker's
        // (GpuMeshBaker::surface).
        std::shared_ptr<RtsdfDeviceState> device;
    };
    std::vector<Mesh> meshes;
    std::vector<MeshPrimaryMesh> views;  // filled by view()

    // Views of the meshes' arrays (valid while this lives and is not changed).
    MeshPrimaryView view() {
        views.clear();
        for (const Mesh& m : meshes) {
            SDFT_CHECK(!m.device);  // its arrays are on the GPU
            views.push_back(
                {{m.nodes.data(), m.triangles.data(), static_cast<int>(m.triangles.size())},
                 m.normals.data(),
                 m.indices.data(),
                 m.toLocal,
                 m.normalToWorld,
                 m.bias});
        }
        return {views.data(), static_cast<int>(views.size())};
    }
};

class MeshPrimary {
  public:
    virtual ~MeshPrimary() = default;

    using Hit = MeshPrimaryHit;
    // The nearest triangle hit with t < tMax (t = +inf when there is none).
    virtual Hit firstHit(const Ray& ray, float tMax) const = 0;
    // The meshes as the per-pixel path traces them: an LBVH per mesh (built on each call) and the
    // placement as affine maps.
    virtual MeshPrimaryTables tables() const = 0;
};

}  // namespace sdft
