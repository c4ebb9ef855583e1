#include "sdftrace/bake/exact_bake.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <memory>

#include "sdftrace/bake/winding_number.h"

namespace sdft {

std::vector<float> bakeExactSamples(const MeshBvh& bvh, const GridShape& s, SignMethod sign,
                                    int threads) {
    std::unique_ptr<WindingNumber> winding;
    if (sign == SignMethod::WindingNumber) winding = std::make_unique<WindingNumber>(bvh.mesh());
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
                        bool inside = winding ? winding->inside(p) : bvh.insideByParity(p);
                        out[static_cast<size_t>(row) * vx + i] = inside ? -d : d;
                    }
                }
            });
    });
    return out;
}

Grid bakeMeshExact(const TriangleMesh& mesh, const SampleOptions& o, SignMethod sign) {
    MeshBvh bvh(mesh);
    GridShape shape = gridShapeFor(mesh.bounds(), o);
    std::vector<float> samples = bakeExactSamples(bvh, shape, sign, o.threads);
    if (o.kind == GridKind::Dense) return Grid::dense(shape, std::move(samples));
    return Grid::sparseFromDense(shape, samples, o.blockSize, o.bandVoxels);
}

}  // namespace sdft
