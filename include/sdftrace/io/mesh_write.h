// Triangle meshes to files: binary little-endian PLY, Wavefront OBJ (text, shortest round-trip
// floats) or binary STL, by extension. Written atomically (io/atomic_file.h): the file appears
// whole or not at all.
#pragma once

#include <string>

#include "sdftrace/bake/triangle_mesh.h"

namespace sdft {

// .ply, .obj or .stl (case-insensitive).
bool isMeshOutputFile(const std::string& path);

// Throws InputError naming the file on an unsupported extension or a failed write.
void saveMesh(const TriangleMesh& mesh, const std::string& path);

}  // namespace sdft
