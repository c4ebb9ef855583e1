// The closest point transform (Mauch, "A fast algorithm for computing the closest point and
// distance transform", 2000; Mauch's thesis 2003, ch. 3): the exact unsigned distance from every
// vertex of a dense grid to a triangle mesh, without a search per vertex.
//
// Every point's closest point on the mesh lies inside a face, inside an edge or at a vertex, and
// then the point lies in that feature's characteristic region:
//  - face: the prism swept by the triangle along its normal;
//  - edge: the slab between the planes through its ends perpendicular to it, on the outer side
//    of every face that holds it (the point projects outside each such face across the edge);
//  - vertex: the cone { x : (x - v) . e <= 0 } for every edge e leaving it.
// These are convex polyhedra; each is cut to the grid and to the largest distance any vertex can
// have (bounded from a coarse lattice), and scan-converted row by row, keeping per vertex the
// minimum distance to the features whose region holds it. The minimum is exact: the distances are
// to parts of the mesh (never below the true one), and the true closest feature is among them.
// Regions are grown by a hair (1e-3 voxel) so rounding cannot drop the closest feature. Work is
// the regions' total volume (a few times the grid's) instead of a tree search per vertex.
#pragma once

#include <cstddef>

#include "sdftrace/bake/triangle_mesh.h"
#include "sdftrace/field/grid.h"

namespace sdft {

class Progress;

struct ClosestPointTransformStats {
    size_t faces = 0, edges = 0, vertices = 0;  // features with a non-empty region in the grid
    size_t rows = 0;                            // scan-converted rows
    size_t evaluations = 0;                     // feature-to-vertex distances computed
    float maxDistance = 0;                      // the bound regions were cut to (world units)
};

// Writes the distance from every vertex of `shape` (x fastest) to the mesh into `out` (world
// units). Runs on the calling task arena; `progress` (may be null) advances by shape.vertices(2) +
// shape.vertices(1) in total.
void closestPointTransform(const TriangleMesh& mesh, const GridShape& shape, float* out,
                           ClosestPointTransformStats* stats = nullptr,
                           Progress* progress = nullptr);

}  // namespace sdft
