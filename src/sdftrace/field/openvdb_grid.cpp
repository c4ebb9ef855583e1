#include "openvdb_grid.h"

#include <openvdb/tools/SignedFloodFill.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>

namespace sdft {

void initOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

float openVdbBand(const Grid& grid) {
    const GridShape& s = grid.shape();
    return grid.kind() == GridKind::Sparse ? grid.background() + s.voxelSize : 3.0f * s.voxelSize;
}

openvdb::FloatGrid::Ptr toOpenVdbGrid(const Grid& grid) {
    initOpenVdb();
    const GridShape& s = grid.shape();
    const GridView v = grid.view();
    const float band = openVdbBand(grid);
    auto out = openvdb::FloatGrid::create(band);
    out->setName("surface");
    out->setGridClass(openvdb::GRID_LEVEL_SET);
    auto xf = openvdb::math::Transform::createLinearTransform(s.voxelSize);
    xf->postTranslate(openvdb::Vec3d(s.origin.x, s.origin.y, s.origin.z));
    out->setTransform(xf);

    // One tree per worker over z-slabs (dense: vertex planes; sparse: block layers), merged at the
    // end; the shared vertices of neighbouring blocks hold the same sample, so the merge order does
    // not matter.
    using Tree = openvdb::FloatTree;
    tbb::enumerable_thread_specific<Tree> trees([band] { return Tree(band); });
    auto put = [&](openvdb::tree::ValueAccessor<Tree>& acc, int i, int j, int k) {
        const float value = v.vertex(i, j, k);
        if (grid.kind() == GridKind::Dense && std::fabs(value) >= band) return;
        acc.setValue(openvdb::Coord(i, j, k), std::clamp(value, -band, band));
    };
    if (grid.kind() == GridKind::Dense) {
        tbb::parallel_for(tbb::blocked_range<int>(0, s.cells[2] + 1),
                          [&](const tbb::blocked_range<int>& r) {
                              openvdb::tree::ValueAccessor<Tree> acc(trees.local());
                              for (int k = r.begin(); k != r.end(); ++k)
                                  for (int j = 0; j <= s.cells[1]; ++j)
                                      for (int i = 0; i <= s.cells[0]; ++i) put(acc, i, j, k);
                          });
    } else {
        const int B = v.blockSize;
        tbb::parallel_for(
            tbb::blocked_range<int>(0, v.blocks[2]), [&](const tbb::blocked_range<int>& r) {
                openvdb::tree::ValueAccessor<Tree> acc(trees.local());
                for (int bk = r.begin(); bk != r.end(); ++bk)
                    for (int bj = 0; bj < v.blocks[1]; ++bj)
                        for (int bi = 0; bi < v.blocks[0]; ++bi) {
                            const size_t block =
                                (static_cast<size_t>(bk) * v.blocks[1] + bj) * v.blocks[0] + bi;
                            if (v.blockData[block] < 0) continue;
                            for (int k = bk * B; k <= std::min((bk + 1) * B, s.cells[2]); ++k)
                                for (int j = bj * B; j <= std::min((bj + 1) * B, s.cells[1]); ++j)
                                    for (int i = bi * B; i <= std::min((bi + 1) * B, s.cells[0]);
                                         ++i)
                                        put(acc, i, j, k);
                        }
            });
    }
    for (Tree& t : trees) out->tree().merge(t, openvdb::MERGE_ACTIVE_STATES);
    openvdb::tools::signedFloodFill(out->tree());
    return out;
}

}  // namespace sdft
