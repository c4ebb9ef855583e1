// Raw float32 grids: PATH holds the samples (little-endian float32, x fastest, no header) and
// PATH.json the sidecar that says what they are:
//   {"format": "sdftrace-raw-float32", "dims": [nx, ny, nz], "origin": [x, y, z],
//    "voxel_size": h}
// (dims are samples per axis; sample (i, j, k) sits at origin + (i, j, k) h). What volume tools
// and numpy (np.fromfile(PATH, "<f4").reshape(nz, ny, nx)) read and write. docs/file-formats.md.
#pragma once

#include <string>

#include "sdftrace/field/grid.h"

namespace sdft {

std::string rawSidecarPath(const std::string& rawPath);  // rawPath + ".json"
// Throws InputError naming the sidecar or the raw file for anything missing or inconsistent.
Grid loadRawGrid(const std::string& path);
// Writes both files, each atomically (the sidecar last).
void saveRawGrid(const Grid& grid, const std::string& path);

}  // namespace sdft
