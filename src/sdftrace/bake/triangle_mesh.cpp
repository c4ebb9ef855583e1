#include "sdftrace/bake/triangle_mesh.h"

#include <algorithm>
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

}  // namespace sdft
