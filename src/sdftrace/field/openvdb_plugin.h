// OpenVDB's tools as a plugin (docs/decisions/0008-openvdb-as-a-plugin.md): writing .vdb files and
// volumeToMesh live in libsdftrace_openvdb.so, loaded on first use, so that the commands that do
// not need them (render, info, bake to .sdfg, reading .vdb, which sdftrace parses itself) do not
// load libopenvdb, whose 52,000 load-time relocations cost every process about 25 ms.
//
// The same header declares the plugin's table (built by src/plugins/openvdb/openvdb_plugin.cpp)
// and the loader. Only GridView (header-only) crosses the boundary, so the plugin needs no symbol
// of this library.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "sdftrace/field/grid.h"

namespace sdft {

// A grid as OpenVDB sees it: vertex (i, j, k) is VDB index (i, j, k); the transform scales by the
// voxel size and translates to the origin. The level set (class GRID_LEVEL_SET, name "surface")
// holds the real samples (a sparse grid's surface blocks, a dense grid's samples within the band),
// clamped to +-band, signed-flood-filled outside them; band = a sparse grid's background plus one
// voxel, or 3 voxels for a dense grid.
struct OpenVdbPlugin {
    static constexpr int kVersion = 1;
    int version = 0;
    // The half width of the level set's band in world units.
    float (*band)(const GridView& grid) = nullptr;
    // The .vdb file's bytes; false with `error` set on failure.
    bool (*encodeVdb)(const GridView& grid, std::string& bytes, std::string& error) = nullptr;
    // openvdb::tools::volumeToMesh at `isovalue` with `adaptivity` (its winding: clockwise seen
    // from outside), with the seconds spent converting and contouring; false with `error` set on
    // failure.
    bool (*volumeToMesh)(const GridView& grid, float isovalue, float adaptivity,
                         std::vector<std::array<float, 3>>& points,
                         std::vector<std::array<uint32_t, 3>>& triangles,
                         std::vector<std::array<uint32_t, 4>>& quads, double seconds[2],
                         std::string& error) = nullptr;
};

// The plugin's table, loaded once (thread-safe). Searched in $SDFT_PLUGIN_DIR when it is set, else
// beside the running executable, then in the build tree; throws InputError naming `purpose` and
// the places searched when it is missing or of another version.
const OpenVdbPlugin& openVdbPlugin(const std::string& purpose);

}  // namespace sdft

// The plugin's one exported symbol.
extern "C" const sdft::OpenVdbPlugin* sdftrace_openvdb_plugin();
