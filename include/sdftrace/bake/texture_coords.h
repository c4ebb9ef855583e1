// Projected texture coordinates precomputed into a grid (Liktor 2008, §4.2.2 and §5.5.2, after
// Wyvill et al.'s particle-based texturing): from every stored sample near the surface a particle
// follows the gradient of the field out to a helper surface that encloses the object (a sphere or
// a cylinder); where it leaves the helper is stored beside the distance, and the renderer maps
// the interpolated point to (u, v) by the helper's parameterization (GridView::texcoordsAt).
// Storing the 3D exit point in the helper's frame rather than (u, v) keeps the interpolation free
// of the seam where u wraps from 1 to 0.
#pragma once

#include <cmath>
#include <functional>
#include <string>

#include "sdftrace/field/grid.h"

namespace sdft {

struct TexcoordOptions {
    TexcoordKind helper = TexcoordKind::Sphere;
    bool autoCenter = true;  // the centre of the grid's surface bounds
    Vec3 center{0, 0, 0};
    Vec3 axis{0, 1, 0};       // the sphere's poles, the cylinder's axis
    float bandVoxels = 2.5f;  // samples traced: |f| <= band voxels (the rest: radial projection)
    int maxSteps = 4096;      // per particle
    // Particles stop where the field reaches this level and are projected radially from there:
    // for a narrow-band grid's reconstruction, which is no distance beyond its band (clamped,
    // then constant), a level inside the band.
    float stopLevel = INFINITY;
    int threads = 0;  // 0: all cores
};

struct TexcoordStats {
    size_t particles = 0;   // samples traced
    size_t projected = 0;   // samples outside the band (radial projection)
    size_t unfinished = 0;  // particles out of steps (their last point is projected)
    size_t ridges = 0;      // particles stopped where the field stopped rising (then projected)
    size_t atLevel = 0;     // particles stopped at `stopLevel` (then projected)
    double meanSteps = 0;
    double fieldEvaluations = 0;  // per particle
    Vec3 center;                  // the helper's
    float radius = 0;             // the helper's (sphere: radius; cylinder: radial)
};

// Helper names as in scene files and flags: "sphere", "cylinder" (None: "none").
const char* texcoordKindName(TexcoordKind kind);
bool parseTexcoordKind(const std::string& s, TexcoordKind& out);  // sphere or cylinder only

// The helper frame: e1, e2 span the plane across `axis`, e1 x e2 = axis.
void helperFrame(Vec3 axis, Vec3& e1, Vec3& e2);

// Traces the particles of `grid`'s stored samples along the gradient of `field` (the scene's
// field, or the grid's own reconstruction for meshes) and attaches the texture coordinates.
TexcoordStats bakeTexcoords(Grid& grid, const std::function<float(Vec3)>& field,
                            const TexcoordOptions& options);

}  // namespace sdft
