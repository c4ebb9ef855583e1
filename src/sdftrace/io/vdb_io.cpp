#include "sdftrace/io/vdb_io.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/SignedFloodFill.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <sstream>

#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/io/atomic_file.h"

namespace sdft {

namespace {
void initOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}
}  // namespace

Grid loadVdb(const std::string& path, const VdbImportOptions& options) {
    initOpenVdb();
    openvdb::GridPtrVecPtr grids;
    try {
        openvdb::io::File file(path);
        file.open();
        grids = file.getGrids();
        file.close();
    } catch (const std::bad_alloc&) {
        // OpenVDB allocates the sizes a file states; a corrupt one can ask for exabytes (refused
        // by the allocation guard of the CLI once over the memory budget).
        throw InputError(path + ": cannot read OpenVDB file: a size in it asks for more memory " +
                         "than the budget of " + formatBytes(memoryBudgetBytes()) +
                         " (a corrupt file, or raise --max-memory)");
    } catch (const std::exception& e) {
        throw InputError(path + ": cannot read OpenVDB file (" + e.what() + ")");
    }
    openvdb::FloatGrid::Ptr grid;
    for (const auto& g : *grids) {
        auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
        if (!f) continue;
        if (!grid || (f->getGridClass() == openvdb::GRID_LEVEL_SET &&
                      grid->getGridClass() != openvdb::GRID_LEVEL_SET))
            grid = f;
    }
    if (!grid)
        throw InputError(path + ": no float grid in the file (accepted: a FloatGrid level set)");
    const openvdb::math::Transform& xf = grid->transform();
    openvdb::Vec3d vs = xf.voxelSize();
    if (!xf.isLinear() || std::fabs(vs[0] - vs[1]) > 1e-6 * vs[0] ||
        std::fabs(vs[0] - vs[2]) > 1e-6 * vs[0]) {
        throw InputError(path + ": grid '" + grid->getName() +
                         "' has a non-uniform or non-linear transform (accepted: uniform voxels)");
    }
    openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
    if (box.empty())
        throw InputError(path + ": grid '" + grid->getName() + "' has no active voxels");
    openvdb::Coord dim = box.dim();
    for (int a = 0; a < 3; ++a) {
        if (dim[a] < 2 || dim[a] > 32768)
            throw InputError(path + ": active region of " + std::to_string(dim[a]) +
                             " voxels along an axis (accepted: 2 to 32768)");
    }
    GridShape shape;
    const float h = static_cast<float>(vs[0]);
    openvdb::Vec3d origin = xf.indexToWorld(box.min());
    for (int a = 0; a < 3; ++a) {
        shape.cells[a] = dim[a] - 1;
        shape.origin[a] = static_cast<float>(origin[a]);
    }
    shape.voxelSize = h;
    checkMemoryBudget(2.0 * static_cast<double>(shape.vertexCount()) * sizeof(float), path,
                      "the active region of " + std::to_string(dim[0]) + "x" +
                          std::to_string(dim[1]) + "x" + std::to_string(dim[2]) +
                          " voxels, imported through a dense array",
                      "resample the level set coarser");
    std::vector<float> samples(shape.vertexCount());
    auto acc = grid->getConstAccessor();
    size_t n = 0;
    for (int k = 0; k < dim[2]; ++k)
        for (int j = 0; j < dim[1]; ++j)
            for (int i = 0; i < dim[0]; ++i)
                samples[n++] = acc.getValue(box.min().offsetBy(i, j, k));
    for (float v : samples)
        if (!std::isfinite(v))
            throw InputError(path + ": non-finite values in grid '" + grid->getName() + "'");
    // Samples equal to the background are outside the band by definition; keep rounding in
    // band * h from making them look near.
    float band = std::max(options.minBandVoxels, std::fabs(grid->background()) / h * 0.999f);
    return Grid::sparseFromDense(shape, samples, options.blockSize, band);
}

void saveVdb(const Grid& grid, const std::string& path) {
    initOpenVdb();
    const GridShape& s = grid.shape();
    GridView v = grid.view();
    // Level sets keep a narrow band of about 3 voxels; ours is the sparse grid's band (its
    // background plus one voxel) or 3 voxels for dense grids.
    float band =
        grid.kind() == GridKind::Sparse ? grid.background() + s.voxelSize : 3.0f * s.voxelSize;
    auto out = openvdb::FloatGrid::create(band);
    out->setName("surface");
    out->setGridClass(openvdb::GRID_LEVEL_SET);
    auto xf = openvdb::math::Transform::createLinearTransform(s.voxelSize);
    xf->postTranslate(openvdb::Vec3d(s.origin.x, s.origin.y, s.origin.z));
    out->setTransform(xf);
    auto acc = out->getAccessor();
    // Only real samples become active: a sparse grid's surface blocks (its other blocks hold no
    // samples), a dense grid's samples within the band. Values are clamped to +-band as level sets
    // expect.
    auto put = [&](int i, int j, int k) {
        float value = v.vertex(i, j, k);
        if (grid.kind() == GridKind::Dense && std::fabs(value) >= band) return;
        acc.setValue(openvdb::Coord(i, j, k), std::clamp(value, -band, band));
    };
    if (grid.kind() == GridKind::Dense) {
        for (int k = 0; k <= s.cells[2]; ++k)
            for (int j = 0; j <= s.cells[1]; ++j)
                for (int i = 0; i <= s.cells[0]; ++i) put(i, j, k);
    } else {
        const int B = v.blockSize;
        for (int bk = 0; bk < v.blocks[2]; ++bk)
            for (int bj = 0; bj < v.blocks[1]; ++bj)
                for (int bi = 0; bi < v.blocks[0]; ++bi) {
                    size_t block = (static_cast<size_t>(bk) * v.blocks[1] + bj) * v.blocks[0] + bi;
                    if (v.blockData[block] < 0) continue;
                    for (int k = bk * B; k <= std::min((bk + 1) * B, s.cells[2]); ++k)
                        for (int j = bj * B; j <= std::min((bj + 1) * B, s.cells[1]); ++j)
                            for (int i = bi * B; i <= std::min((bi + 1) * B, s.cells[0]); ++i)
                                put(i, j, k);
                }
    }
    openvdb::tools::signedFloodFill(out->tree());
    // Encoded in memory, then written with every write checked.
    std::ostringstream bytes(std::ios::binary);
    try {
        openvdb::GridPtrVec grids{out};
        openvdb::io::Stream(bytes).write(grids);
    } catch (const std::exception& e) {
        throw InputError(path + ": cannot write OpenVDB file (" + e.what() + ")");
    }
    const std::string data = bytes.str();
    writeFileAtomically(path, data.data(), data.size());
}

}  // namespace sdft
