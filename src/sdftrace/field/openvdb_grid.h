// sdftrace grids as OpenVDB float level sets, for writing .vdb files and for OpenVDB's tools
// (volumeToMesh). Vertex (i, j, k) becomes VDB index (i, j, k); the transform scales by the voxel
// size and translates to the grid's origin.
#pragma once

#include <openvdb/openvdb.h>

#include "sdftrace/field/grid.h"

namespace sdft {

// Calls openvdb::initialize() once.
void initOpenVdb();

// The level set's half width in world units: a sparse grid's band (its background plus one voxel)
// or 3 voxels for dense grids.
float openVdbBand(const Grid& grid);

// A level set (class GRID_LEVEL_SET, name "surface") whose active voxels are the real samples (a
// sparse grid's surface blocks, a dense grid's samples within the band), clamped to +-band, with a
// signed flood fill outside them. Built in parallel, one tree per worker, merged.
openvdb::FloatGrid::Ptr toOpenVdbGrid(const Grid& grid);

}  // namespace sdft
