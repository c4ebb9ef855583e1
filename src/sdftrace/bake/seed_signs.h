// Signs for the propagation bakes (jump flooding, Danielsson, the separable EDT): their distances
// are unsigned, so inside and outside come from one of the SignMethods.
#pragma once

#include <vector>

#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/bake/sign_method.h"
#include "sdftrace/bake/surface_seeds.h"

namespace sdft {

// `distances` (unsigned) signed in place. `bvh` is needed for RayParity only; `betaVoxels` for
// BetaShell only.
void signDistances(std::vector<float>& distances, const TriangleMesh& mesh, const MeshBvh* bvh,
                   const GridShape& shape, const SurfaceSeeds& seeds, SignMethod method,
                   float betaVoxels = 0.5f, int threads = 0);

// The same for a sparse grid with blocks of B cells and a band of `bandVoxels`: only the vertices
// of blocks with a sample within the band get their own sign; a block with none holds no surface
// (it would pass within half a cell diagonal of a vertex) and takes the sign at its centre, as the
// exact narrow-band bake does. Flood and beta signs sign everything.
void signDistancesSparse(std::vector<float>& distances, const TriangleMesh& mesh,
                         const MeshBvh* bvh, const GridShape& shape, const SurfaceSeeds& seeds,
                         SignMethod method, float betaVoxels, int blockSize, float bandVoxels,
                         int threads = 0);

// SignMethod::FloodFill alone: 1 where inside.
std::vector<uint8_t> floodFillInside(const TriangleMesh& mesh, const GridShape& shape,
                                     const SurfaceSeeds& seeds);

}  // namespace sdft
