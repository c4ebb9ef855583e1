#include "sdftrace/scene/mesh_accel.h"

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

MeshAccel::MeshAccel(std::shared_ptr<const TriangleMesh> mesh)
    : m_mesh(std::move(mesh)), m_bvh(*m_mesh), m_normals(smoothNormals(*m_mesh)) {}

const MeshAccel::LbvhArrays& MeshAccel::lbvh() const {
    std::call_once(m_lbvhOnce, [&] {
        const Lbvh bvh(*m_mesh);
        m_lbvh.nodes = bvh.nodes();
        m_lbvh.triangles = bvh.triangles();
        m_lbvh.indices.reserve(3 * m_mesh->triangles.size());
        for (const auto& tri : m_mesh->triangles)
            m_lbvh.indices.insert(m_lbvh.indices.end(), tri.begin(), tri.end());
    });
    return m_lbvh;
}

}  // namespace sdft
