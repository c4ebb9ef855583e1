#include "sdftrace/bake/seed_signs.h"

#include "sdftrace/bake/winding_number.h"
#include "sdftrace/core/macros.h"
#include "sdftrace/field/vertex_loop.h"

namespace sdft {

const char* signMethodName(SignMethod m) {
    switch (m) {
        case SignMethod::WindingNumber:
            return "winding number";
        case SignMethod::RayParity:
            return "ray parity";
        case SignMethod::FloodFill:
            return "flood fill";
        case SignMethod::BetaShell:
            return "beta shell";
    }
    return "?";
}

std::vector<uint8_t> floodFillInside(const TriangleMesh& mesh, const GridShape& s,
                                     const SurfaceSeeds& seeds) {
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    const size_t count = s.vertexCount();
    // A surface passing between two neighbours comes within h/2 of one of them, which is then a
    // seed (reach 0.87 h): 6-connected paths of non-seeds never cross it.
    std::vector<uint8_t> inside(count, 1);
    std::vector<size_t> stack;
    auto push = [&](int i, int j, int k) {
        size_t idx = (static_cast<size_t>(k) * vy + j) * vx + i;
        if (!inside[idx] || seeds.point[idx].x != kNoSeed) return;
        inside[idx] = 0;
        stack.push_back(idx);
    };
    for (int k = 0; k < vz; ++k)
        for (int j = 0; j < vy; ++j)
            for (int i = 0; i < vx; ++i)
                if (i == 0 || j == 0 || k == 0 || i == vx - 1 || j == vy - 1 || k == vz - 1)
                    push(i, j, k);
    while (!stack.empty()) {
        size_t idx = stack.back();
        stack.pop_back();
        int i = static_cast<int>(idx % vx), j = static_cast<int>((idx / vx) % vy),
            k = static_cast<int>(idx / (static_cast<size_t>(vx) * vy));
        if (i > 0) push(i - 1, j, k);
        if (i + 1 < vx) push(i + 1, j, k);
        if (j > 0) push(i, j - 1, k);
        if (j + 1 < vy) push(i, j + 1, k);
        if (k > 0) push(i, j, k - 1);
        if (k + 1 < vz) push(i, j, k + 1);
    }
    // Seeds: the side of their closest triangle's normal where the closest point is inside the
    // face. On an edge or a corner the face normal can point the wrong way (the pseudo-normal
    // problem); those few take the winding number's answer.
    std::unique_ptr<WindingNumber> winding;
    for (size_t idx = 0; idx < count; ++idx) {
        if (seeds.point[idx].x == kNoSeed) continue;
        const auto& t = mesh.triangles[seeds.triangle[idx]];
        Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
        int i = static_cast<int>(idx % vx), j = static_cast<int>((idx / vx) % vy),
            k = static_cast<int>(idx / (static_cast<size_t>(vx) * vy));
        Vec3 p = s.origin + Vec3(i, j, k) * s.voxelSize, q = seeds.point[idx];
        Vec3 n = cross(b - a, c - a);
        float area2 = dot(n, n);
        float u = dot(cross(c - b, q - b), n) / area2, v = dot(cross(a - c, q - c), n) / area2,
              w = 1 - u - v;
        if (std::fmin(u, std::fmin(v, w)) > 1e-4f) {
            inside[idx] = dot(p - q, n) < 0;
        } else {
            if (!winding) winding = std::make_unique<WindingNumber>(mesh);
            inside[idx] = winding->inside(p);
        }
    }
    return inside;
}

void signDistances(std::vector<float>& d, const TriangleMesh& mesh, const MeshBvh* bvh,
                   const GridShape& s, const SurfaceSeeds& seeds, SignMethod method,
                   float betaVoxels, int threads) {
    SDFT_CHECK(d.size() == s.vertexCount());
    if (method == SignMethod::BetaShell) {
        const float beta = betaVoxels * s.voxelSize;
        for (float& v : d) v = std::fabs(v) - beta;
        return;
    }
    if (method == SignMethod::FloodFill) {
        std::vector<uint8_t> inside = floodFillInside(mesh, s, seeds);
        for (size_t i = 0; i < d.size(); ++i) d[i] = inside[i] ? -std::fabs(d[i]) : std::fabs(d[i]);
        return;
    }
    SDFT_CHECK(method == SignMethod::WindingNumber || bvh != nullptr);
    std::unique_ptr<WindingNumber> winding;
    if (method == SignMethod::WindingNumber) winding = std::make_unique<WindingNumber>(mesh);
    forEachVertex(s, threads, [&](int, int, int, size_t idx, Vec3 p) {
        bool in = winding ? winding->inside(p) : bvh->insideByParity(p);
        d[idx] = in ? -std::fabs(d[idx]) : std::fabs(d[idx]);
    });
}

}  // namespace sdft
