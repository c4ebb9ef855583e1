#include "sdftrace/bake/extract_surface.h"

#include <openvdb/tools/VolumeToMesh.h>

#include <chrono>
#include <cmath>
#include <cstdio>

#include "../field/openvdb_grid.h"
#include "sdftrace/core/error.h"

namespace sdft {

namespace {
std::string number(float v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

double since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

TriangleMesh extractSurface(const Grid& grid, const ExtractOptions& o, const std::string& source,
                            ExtractStats* stats) {
    if (!(o.adaptivity >= 0 && o.adaptivity <= 1))
        throw InputError("--adaptivity " + number(o.adaptivity) + ": accepted values are 0 to 1");
    const float band = openVdbBand(grid);
    const float voxel = grid.shape().voxelSize;
    // Samples are clamped to +-band; an isovalue within a voxel of it is not a surface of the
    // field.
    if (!(std::fabs(o.isovalue) < band - voxel))
        throw InputError("--isovalue " + number(o.isovalue) + ": " + source +
                         " stores distances within +-" + number(band - voxel) +
                         " of the surface only (its narrow band); bake a wider --band for offset "
                         "surfaces farther out");
    auto t0 = std::chrono::steady_clock::now();
    openvdb::FloatGrid::Ptr vdb = toOpenVdbGrid(grid);
    const double convertSeconds = since(t0);
    t0 = std::chrono::steady_clock::now();
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> tris;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(*vdb, points, tris, quads, o.isovalue, o.adaptivity);
    vdb.reset();
    if (tris.empty() && quads.empty())
        throw InputError(source + ": no surface at isovalue " + number(o.isovalue) +
                         " (the field does not change sign there)");

    TriangleMesh mesh;
    mesh.positions.reserve(points.size());
    for (const auto& p : points) mesh.positions.push_back({p.x(), p.y(), p.z()});
    mesh.triangles.reserve(tris.size() + 2 * quads.size());
    // volumeToMesh winds its polygons clockwise seen from outside; ours are counter-clockwise.
    for (const auto& t : tris) mesh.triangles.push_back({t[0], t[2], t[1]});
    for (const auto& q : quads) {
        // The shorter diagonal splits the quad (less sliver-prone on curved regions).
        const Vec3 a = mesh.positions[q[0]], b = mesh.positions[q[1]], c = mesh.positions[q[2]],
                   d = mesh.positions[q[3]];
        if (dot(a - c, a - c) <= dot(b - d, b - d)) {
            mesh.triangles.push_back({q[0], q[2], q[1]});
            mesh.triangles.push_back({q[0], q[3], q[2]});
        } else {
            mesh.triangles.push_back({q[0], q[3], q[1]});
            mesh.triangles.push_back({q[1], q[3], q[2]});
        }
    }
    if (stats) {
        stats->quads = quads.size();
        stats->triangles = tris.size();
        stats->convertSeconds = convertSeconds;
        stats->contourSeconds = since(t0);
    }
    return mesh;
}

}  // namespace sdft
