#include "sdftrace/bake/surface_seeds.h"

#include <tbb/parallel_for.h>

#include <cmath>

#include "sdftrace/bake/closest_point.h"
#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/exec/thread_arena.h"
#include "sdftrace/field/vertex_loop.h"

namespace sdft {

SurfaceSeeds seedSurfaceVertices(const TriangleMesh& mesh, const GridShape& s, int threads) {
    const int vz = s.vertices(2);
    const float h = s.voxelSize, reach = seedReach(s);
    SurfaceSeeds seeds;
    assignHuge(seeds.point, s.vertexCount(), Vec3(kNoSeed));
    assignHuge(seeds.triangle, s.vertexCount(), 0u);
    std::vector<float> best;
    assignHuge(best, s.vertexCount(), kNoSeed);
    // Vertex ranges of each triangle's bounds (one voxel of margin covers the reach).
    std::vector<VertexRange> ranges(mesh.triangles.size());
    constexpr int kSlab = 4;  // z layers per task
    const int slabs = (vz + kSlab - 1) / kSlab;
    std::vector<std::vector<uint32_t>> bySlab(slabs);
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const auto& tri = mesh.triangles[t];
        const VertexRange& r = ranges[t] = triangleVertexRange(
            s, mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]], h);
        if (r.empty()) continue;
        for (int slab = r.lo[2] / kSlab; slab <= r.hi[2] / kSlab; ++slab)
            bySlab[slab].push_back(static_cast<uint32_t>(t));
    }
    ThreadArena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(0, slabs, [&](int slab) {
            const int k0 = slab * kSlab, k1 = std::min(vz - 1, k0 + kSlab - 1);
            for (uint32_t t : bySlab[slab]) {
                const auto& tri = mesh.triangles[t];
                Vec3 a = mesh.positions[tri[0]], b = mesh.positions[tri[1]],
                     c = mesh.positions[tri[2]];
                const VertexRange& r = ranges[t];
                for (int k = std::max(k0, r.lo[2]); k <= std::min(k1, r.hi[2]); ++k)
                    for (int j = r.lo[1]; j <= r.hi[1]; ++j)
                        for (int i = r.lo[0]; i <= r.hi[0]; ++i) {
                            Vec3 p = vertexPosition(s, i, j, k);
                            Vec3 q = closestPointOnTriangle(p, a, b, c);
                            float d = length(p - q);
                            size_t idx = vertexIndex(s, i, j, k);
                            if (d <= reach && d < best[idx]) {
                                best[idx] = d;
                                seeds.point[idx] = q;
                                seeds.triangle[idx] = t;
                            }
                        }
            }
        });
    });
    return seeds;
}

std::vector<float> distancesToPoints(const GridShape& s, const std::vector<Vec3>& points,
                                     int threads) {
    std::vector<float> out;
    assignHuge(out, points.size(), 0.0f);
    forEachVertex(s, threads, [&](int, int, int, size_t idx, Vec3 p) {
        out[idx] = points[idx].x == kNoSeed ? kNoSeed : length(p - points[idx]);
    });
    return out;
}

}  // namespace sdft
