#include "sdftrace/bake/exact_bake.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace sdft {

std::vector<float> bakeExactSamples(const MeshBvh& bvh, const GridShape& s, int threads) {
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    std::vector<float> out(s.vertexCount());
    tbb::task_arena arena(threads > 0 ? threads : tbb::this_task_arena::max_concurrency());
    arena.execute([&] {
        tbb::parallel_for(
            tbb::blocked_range<int>(0, vy * vz), [&](const tbb::blocked_range<int>& rows) {
                for (int row = rows.begin(); row != rows.end(); ++row) {
                    int j = row % vy, k = row / vy;
                    for (int i = 0; i < vx; ++i) {
                        Vec3 p = s.origin + Vec3(i, j, k) * s.voxelSize;
                        float d = bvh.closestDistance(p);
                        out[static_cast<size_t>(row) * vx + i] = bvh.insideByParity(p) ? -d : d;
                    }
                }
            });
    });
    return out;
}

Grid bakeMeshExact(const TriangleMesh& mesh, const SampleOptions& o) {
    MeshBvh bvh(mesh);
    GridShape shape = gridShapeFor(mesh.bounds(), o);
    std::vector<float> samples = bakeExactSamples(bvh, shape, o.threads);
    if (o.kind == GridKind::Dense) return Grid::dense(shape, std::move(samples));
    return Grid::sparseFromDense(shape, samples, o.blockSize, o.bandVoxels);
}

}  // namespace sdft
