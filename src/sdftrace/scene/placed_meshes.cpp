#include "placed_meshes.h"

#include "sdftrace/bake/lbvh.h"

namespace sdft {

MeshPrimary::Hit PlacedMeshes::firstHit(const Ray& ray, float tMax) const {
    Hit best;
    best.t = tMax;
    for (const PlacedMesh& m : m_meshes) {
        SDFT_CHECK(m.accel != nullptr);  // a device mesh's plan is refused by the CPU renderer
        // The ray in the mesh's coordinates, its direction not renormalised so that t stays the
        // world distance through any scale.
        const Vec3 o = m.placement.toLocal(ray.origin);
        const Vec3 d = m.placement.toLocal(ray.origin + ray.direction) - o;
        const MeshBvh::Hit h = m.accel->bvh().firstHit(Ray{o, d});
        if (!(h.t < best.t)) continue;
        const auto& tri = m.mesh->triangles[h.triangle];
        const Vec3 local = m.accel->normals()[tri[0]] * (1 - h.u - h.v) +
                           m.accel->normals()[tri[1]] * h.u + m.accel->normals()[tri[2]] * h.v;
        Vec3 n = m.placement.normalToWorld(length(local) > 0 ? local : Vec3(0, 1, 0));
        if (dot(n, ray.direction) > 0) n = -n;
        best = {h.t, n, m.bias};
    }
    if (!(best.t < tMax)) best.t = INFINITY;
    return best;
}

namespace {

// The affine map p -> f(p) of a placement's map f, from the images of the origin and the axes.
template <class Map>
Affine affineOf(Map&& f) {
    Affine a;
    a.offset = f(Vec3(0.0f));
    for (int j = 0; j < 3; ++j) {
        Vec3 e(0.0f);
        e[j] = 1;
        const Vec3 c = f(e) - a.offset;
        for (int i = 0; i < 3; ++i) a.linear.m[i][j] = c[i];
    }
    return a;
}

}  // namespace

MeshPrimaryTables PlacedMeshes::tables() const {
    MeshPrimaryTables t;
    for (const PlacedMesh& m : m_meshes) {
        MeshPrimaryTables::Mesh out;
        out.device = m.device;
        if (!m.device) {
            const MeshAccel::LbvhArrays& bvh = m.accel->lbvh();
            out.nodes = bvh.nodes;
            out.triangles = bvh.triangles;
            out.normals = m.accel->normals();
            out.indices = bvh.indices;
        }
        out.toLocal = affineOf([&](Vec3 p) { return m.placement.toLocal(p); });
        // The inverse transpose of mesh-to-world's linear part: world-to-mesh's, transposed.
        out.normalToWorld = out.toLocal.linear.transposed();
        out.bias = m.bias;
        t.meshes.push_back(std::move(out));
    }
    return t;
}

}  // namespace sdft
