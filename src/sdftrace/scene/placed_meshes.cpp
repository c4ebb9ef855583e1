#include "placed_meshes.h"

#include "sdftrace/bake/lbvh.h"

namespace sdft {

std::vector<Vec3> smoothNormals(const TriangleMesh& mesh) {
    std::vector<Vec3> n(mesh.positions.size(), Vec3(0.0f));
    for (const auto& t : mesh.triangles) {
        const Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
        const Vec3 area = cross(b - a, c - a);  // twice the area, along the face normal
        for (uint32_t v : t) n[v] += area;
    }
    for (Vec3& v : n) v = length(v) > 0 ? normalize(v) : Vec3(0, 1, 0);
    return n;
}

MeshPrimary::Hit PlacedMeshes::firstHit(const Ray& ray, float tMax) const {
    Hit best;
    best.t = tMax;
    for (const PlacedMesh& m : m_meshes) {
        SDFT_CHECK(m.bvh != nullptr);  // a device mesh's plan is refused by the CPU renderer
        // The ray in the mesh's coordinates, its direction not renormalised so that t stays the
        // world distance through any scale.
        const Vec3 o = m.placement.toLocal(ray.origin);
        const Vec3 d = m.placement.toLocal(ray.origin + ray.direction) - o;
        const MeshBvh::Hit h = m.bvh->firstHit(Ray{o, d});
        if (!(h.t < best.t)) continue;
        const auto& tri = m.mesh->triangles[h.triangle];
        const Vec3 local =
            m.normals[tri[0]] * (1 - h.u - h.v) + m.normals[tri[1]] * h.u + m.normals[tri[2]] * h.v;
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
            const Lbvh bvh(*m.mesh);
            out.nodes = bvh.nodes();
            out.triangles = bvh.triangles();
            out.normals = m.normals;
            out.indices.reserve(3 * m.mesh->triangles.size());
            for (const auto& tri : m.mesh->triangles)
                out.indices.insert(out.indices.end(), tri.begin(), tri.end());
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
