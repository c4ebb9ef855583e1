// How a mesh bake decides inside from outside.
#pragma once

#include <string>

namespace sdft {

enum class SignMethod {
    WindingNumber,  // generalized winding number > 1/2 (robust on open meshes; the default)
    RayParity,      // majority of three ray-crossing parities (closed meshes only)
    FloodFill,      // seed-based bakes: vertices not reachable from the grid's boundary without
                    // crossing the voxelized surface are inside (OpenVDB's approach); seed vertices
                    // take the side of their closest triangle's normal (the winding number where
                    // the closest point is on an edge or corner)
    BetaShell,      // RTSDF §2.2: |d| - beta, a shell around the surface, hollow inside
};

const char* signMethodName(SignMethod m);
// "winding", "parity", "flood", "beta" (the CLI's and scene files' names); false if unknown.
bool parseSignMethod(const std::string& name, SignMethod& out);
constexpr const char* kSignMethods = "winding, parity, flood, beta";

}  // namespace sdft
