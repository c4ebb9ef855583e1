// OpenVDB float level sets to and from sdftrace grids, so level sets made by Houdini, OpenVDB tools
// or simulations render here and ours open there. VDB voxel values sit at integer index points;
// they map to our grid vertices (vertex (i, j, k) = VDB index (i, j, k) + the grid's offset), and
// the VDB transform must be a uniform linear scale plus translation.
#pragma once

#include <cstddef>
#include <string>

#include "sdftrace/field/grid.h"

namespace sdft {

struct VdbImportOptions {
    int blockSize = 4;
    float minBandVoxels = 2;  // the sparse band is the level set's half width, at least this
    // Leaves each worker keeps decoded while it gathers blocks (2 KiB each; at least one tile of
    // blocks' worth). 0: 1024, or two tiles' worth if more.
    size_t cachedLeaves = 0;
};

// Loads the first float grid (a level set preferably) of a .vdb file as a sparse block grid
// covering its active voxels. Throws InputError naming the file for anything unusable.
Grid loadVdb(const std::string& path, const VdbImportOptions& options = {});

// Writes a float level set (class GRID_LEVEL_SET, name "surface") with the samples within the band
// active and a signed flood fill outside it. Atomic.
void saveVdb(const Grid& grid, const std::string& path);

}  // namespace sdft
