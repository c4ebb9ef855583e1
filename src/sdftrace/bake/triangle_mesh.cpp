#include "sdftrace/bake/triangle_mesh.h"

#include <algorithm>
#include <cstdio>
#include <utility>

namespace sdft {

Bounds3 TriangleMesh::bounds() const {
    Bounds3 b;
    for (const Vec3& p : positions) b.include(p);
    return b;
}

bool isWatertight(const TriangleMesh& mesh) {
    std::vector<std::pair<uint32_t, uint32_t>> forward, backward;
    for (const auto& t : mesh.triangles)
        for (int e = 0; e < 3; ++e) {
            forward.emplace_back(t[e], t[(e + 1) % 3]);
            backward.emplace_back(t[(e + 1) % 3], t[e]);
        }
    std::sort(forward.begin(), forward.end());
    std::sort(backward.begin(), backward.end());
    return forward == backward;
}

std::string meshRangeProblem(const TriangleMesh& mesh) {
    Bounds3 b;
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t)
            if (v < mesh.positions.size()) b.include(mesh.positions[v]);
    if (b.empty()) return "";
    const float far = std::max(maxComponent(abs(b.lo)), maxComponent(abs(b.hi)));
    const float size = maxComponent(b.extent());
    char buf[320];
    if (!(far <= kMaxMeshCoordinate)) {
        std::snprintf(buf, sizeof buf,
                      "coordinates reach %.3g; the bakers compute in float and accept |x| <= %.0e "
                      "(scale the mesh down)",
                      far, kMaxMeshCoordinate);
        return buf;
    }
    if (!(size >= kMinMeshExtent)) {
        std::snprintf(buf, sizeof buf,
                      "the mesh spans only %.3g; the bakers need at least %.0e across (scale it "
                      "up)",
                      size, kMinMeshExtent);
        return buf;
    }
    if (far > kMaxMeshOffset * size) {
        std::snprintf(buf, sizeof buf,
                      "the mesh spans %.3g but lies %.3g from the origin; float keeps about 7 "
                      "digits, so it must lie within %.0e times its size of the origin (move it "
                      "closer)",
                      size, far, kMaxMeshOffset);
        return buf;
    }
    return "";
}

}  // namespace sdft
