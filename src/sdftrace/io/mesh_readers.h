// sdftrace's own readers for the mesh formats users bring most: PLY (ascii, binary little- and
// big-endian), STL (ascii and binary), OFF and OBJ. Every count a file declares is checked against
// what the file can hold before anything is allocated or read, every index against the vertex
// count, so that a file cut short or with a few bytes changed (what an
// interrupted download leaves) is one InputError "<path>: <what is wrong>" and never a crash or a
// gigabyte allocation. loadMesh (mesh_io.h) uses them and keeps assimp for the other formats.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "sdftrace/math/vec.h"

namespace sdft {

// A mesh file's vertices and triangles as read (polygons triangulated), before cleaning.
struct MeshArrays {
    std::vector<Vec3> positions;
    std::vector<std::array<uint32_t, 3>> triangles;
};

// `path`'s extension in lower case (".ply"), which picks its reader.
std::string lowerExtension(const std::string& path);

// The reader for `path`'s extension (.ply, .stl, .off, .obj, case-insensitive), or null for the
// formats assimp reads.
using MeshReader = MeshArrays (*)(const std::string& path);
MeshReader ownMeshReader(const std::string& path);

// A coordinate read as a double, as a float: beyond float's range it is an infinity (loadMesh
// then names the vertex as not finite), never the undefined behaviour of an overflowing cast.
inline float toFloatCoordinate(double v) {
    constexpr double kMax = 3.4028234663852886e38;  // FLT_MAX
    if (v > kMax) return std::numeric_limits<float>::infinity();
    if (v < -kMax) return -std::numeric_limits<float>::infinity();
    return static_cast<float>(v);  // NaN stays NaN
}

MeshArrays readPly(const std::string& path);
MeshArrays readStl(const std::string& path);
MeshArrays readOff(const std::string& path);
MeshArrays readObj(const std::string& path);

// What assimp is handed (loadMesh's long tail, AnimatedMesh::load) is first held to its
// extension's signature: when the importer of a file's extension declines it, assimp tries every
// other importer on its content, and some of those (Blender's among them) read damaged bytes out
// of bounds. So an importer must claim the extension and, where several do (glTF 1 and 2), one of
// them must recognise the content; a .glb must be its header's length, chunk by chunk, with JSON
// in its first chunk, and a .gltf JSON. Throws InputError naming the file.
void precheckForAssimp(const std::string& path);

}  // namespace sdft
