// libsdftrace_openvdb.so: the OpenVDB tools sdftrace uses (writing .vdb, volumeToMesh), loaded on
// first use by src/sdftrace/field/openvdb_plugin.cpp. It reads grids through GridView only.
#include "sdftrace/field/openvdb_plugin.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <sstream>

namespace sdft {

namespace {

void initOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

float band(const GridView& v) {
    return v.kind == GridKind::Sparse ? v.background + v.shape.voxelSize : 3.0f * v.shape.voxelSize;
}

// Built in parallel, one tree per worker over z-slabs (dense: vertex planes; sparse: block
// layers), merged at the end; the shared vertices of neighbouring blocks hold the same sample, so
// the merge order does not matter.
openvdb::FloatGrid::Ptr toOpenVdbGrid(const GridView& v) {
    initOpenVdb();
    const GridShape& s = v.shape;
    const float halfWidth = band(v);
    auto out = openvdb::FloatGrid::create(halfWidth);
    out->setName("surface");
    out->setGridClass(openvdb::GRID_LEVEL_SET);
    auto xf = openvdb::math::Transform::createLinearTransform(s.voxelSize);
    xf->postTranslate(openvdb::Vec3d(s.origin.x, s.origin.y, s.origin.z));
    out->setTransform(xf);

    using Tree = openvdb::FloatTree;
    tbb::enumerable_thread_specific<Tree> trees([halfWidth] { return Tree(halfWidth); });
    auto put = [&](openvdb::tree::ValueAccessor<Tree>& acc, int i, int j, int k) {
        const float value = v.vertex(i, j, k);
        if (v.kind == GridKind::Dense && std::fabs(value) >= halfWidth) return;
        acc.setValue(openvdb::Coord(i, j, k), std::clamp(value, -halfWidth, halfWidth));
    };
    if (v.kind == GridKind::Dense) {
        tbb::parallel_for(tbb::blocked_range<int>(0, s.cells[2] + 1),
                          [&](const tbb::blocked_range<int>& r) {
                              openvdb::tree::ValueAccessor<Tree> acc(trees.local());
                              for (int k = r.begin(); k != r.end(); ++k)
                                  for (int j = 0; j <= s.cells[1]; ++j)
                                      for (int i = 0; i <= s.cells[0]; ++i) put(acc, i, j, k);
                          });
    } else {
        // The surface blocks, tile by tile: only tiles with a page of their own hold any.
        const int B = v.blockSize;
        const size_t tiles = static_cast<size_t>(v.tiles[0]) * v.tiles[1] * v.tiles[2];
        tbb::parallel_for(tbb::blocked_range<size_t>(0, tiles, 64), [&](const auto& r) {
            openvdb::tree::ValueAccessor<Tree> acc(trees.local());
            for (size_t tile = r.begin(); tile != r.end(); ++tile) {
                if (v.tilePage[tile] < kFirstOwnPage) continue;
                const int t[3] = {
                    static_cast<int>(tile % v.tiles[0]),
                    static_cast<int>(tile / v.tiles[0] % v.tiles[1]),
                    static_cast<int>(tile / (static_cast<size_t>(v.tiles[0]) * v.tiles[1]))};
                forEachBlockOfTile(v.blocks, t[0], t[1], t[2], [&](int bi, int bj, int bk) {
                    if (v.blockData[v.blockSlot(bi, bj, bk)] < 0) return;
                    for (int k = bk * B; k <= std::min((bk + 1) * B, s.cells[2]); ++k)
                        for (int j = bj * B; j <= std::min((bj + 1) * B, s.cells[1]); ++j)
                            for (int i = bi * B; i <= std::min((bi + 1) * B, s.cells[0]); ++i)
                                put(acc, i, j, k);
                });
            }
        });
    }
    for (Tree& t : trees) out->tree().merge(t, openvdb::MERGE_ACTIVE_STATES);
    openvdb::tools::signedFloodFill(out->tree());
    return out;
}

bool encodeVdb(const GridView& grid, std::string& bytes, std::string& error) {
    try {
        openvdb::GridPtrVec grids{toOpenVdbGrid(grid)};
        std::ostringstream out(std::ios::binary);
        openvdb::io::Stream(out).write(grids);
        bytes = out.str();
        return true;
    } catch (const std::exception& e) {
        error = e.what();
        return false;
    }
}

bool volumeToMesh(const GridView& grid, float isovalue, float adaptivity,
                  std::vector<std::array<float, 3>>& points,
                  std::vector<std::array<uint32_t, 3>>& triangles,
                  std::vector<std::array<uint32_t, 4>>& quads, double seconds[2],
                  std::string& error) {
    try {
        using Clock = std::chrono::steady_clock;
        auto t0 = Clock::now();
        openvdb::FloatGrid::Ptr vdb = toOpenVdbGrid(grid);
        seconds[0] = std::chrono::duration<double>(Clock::now() - t0).count();
        t0 = Clock::now();
        std::vector<openvdb::Vec3s> p;
        std::vector<openvdb::Vec3I> t;
        std::vector<openvdb::Vec4I> q;
        openvdb::tools::volumeToMesh(*vdb, p, t, q, isovalue, adaptivity);
        vdb.reset();
        seconds[1] = std::chrono::duration<double>(Clock::now() - t0).count();
        points.resize(p.size());
        for (size_t i = 0; i < p.size(); ++i) points[i] = {p[i].x(), p[i].y(), p[i].z()};
        triangles.resize(t.size());
        for (size_t i = 0; i < t.size(); ++i) triangles[i] = {t[i][0], t[i][1], t[i][2]};
        quads.resize(q.size());
        for (size_t i = 0; i < q.size(); ++i) quads[i] = {q[i][0], q[i][1], q[i][2], q[i][3]};
        return true;
    } catch (const std::exception& e) {
        error = e.what();
        return false;
    }
}

const OpenVdbPlugin kTable{OpenVdbPlugin::kVersion, band, encodeVdb, volumeToMesh};

}  // namespace

}  // namespace sdft

extern "C" __attribute__((visibility("default"))) const sdft::OpenVdbPlugin*
sdftrace_openvdb_plugin() {
    return &sdft::kTable;
}
