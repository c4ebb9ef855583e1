#include "sdftrace/bake/extract_surface.h"

#include <cmath>
#include <cstdio>

#include "sdftrace/core/error.h"
#include "sdftrace/field/openvdb_plugin.h"

namespace sdft {

namespace {
std::string number(float v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

}  // namespace

TriangleMesh extractSurface(const Grid& grid, const ExtractOptions& o, const std::string& source,
                            ExtractStats* stats) {
    if (!(o.adaptivity >= 0 && o.adaptivity <= 1))
        throw InputError("--adaptivity " + number(o.adaptivity) + ": accepted values are 0 to 1");
    const OpenVdbPlugin& openVdb = openVdbPlugin("extracting a mesh");
    const GridView view = grid.view();
    const float band = openVdb.band(view);
    const float voxel = grid.shape().voxelSize;
    // Samples are clamped to +-band; an isovalue within a voxel of it is not a surface of the
    // field.
    if (!(std::fabs(o.isovalue) < band - voxel))
        throw InputError("--isovalue " + number(o.isovalue) + ": " + source +
                         " stores distances within +-" + number(band - voxel) +
                         " of the surface only (its narrow band); bake a wider --band for offset "
                         "surfaces farther out");
    std::vector<std::array<float, 3>> points;
    std::vector<std::array<uint32_t, 3>> tris;
    std::vector<std::array<uint32_t, 4>> quads;
    std::string error;
    double seconds[2] = {0, 0};
    if (!openVdb.volumeToMesh(view, o.isovalue, o.adaptivity, points, tris, quads, seconds, error))
        throw InputError(source + ": OpenVDB's volumeToMesh failed (" + error + ")");
    if (tris.empty() && quads.empty())
        throw InputError(source + ": no surface at isovalue " + number(o.isovalue) +
                         " (the field does not change sign there)");

    TriangleMesh mesh;
    mesh.positions.reserve(points.size());
    for (const auto& p : points) mesh.positions.push_back({p[0], p[1], p[2]});
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
        stats->convertSeconds = seconds[0];
        stats->contourSeconds = seconds[1];
    }
    return mesh;
}

}  // namespace sdft
