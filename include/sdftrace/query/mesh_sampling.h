// Random points for learning signed distances (DeepSDF, Park et al. 2019, §5: surface samples
// perturbed by Gaussian noise of a few widths; occupancy networks: uniform points in a box). Each
// point is drawn from a counter-based generator keyed by (seed, index): the same seed gives the
// same points on any number of threads.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "sdftrace/query/mesh_query.h"

namespace sdft {

// n points on the surface, uniform by area: positions (n x 3), the faces' unit normals (n x 3)
// and face ids (n); any output may be null.
template <class T>
void sampleSurface(const MeshQuery& mesh, size_t n, uint64_t seed, T* points, T* normals,
                   int64_t* faces);

// n surface points, point i moved by an isotropic Gaussian of standard deviation
// sigmas[i % sigmas.size()] (n x 3 out). sigmas: finite, >= 0, at least one.
template <class T>
void sampleNearSurface(const MeshQuery& mesh, size_t n, const std::vector<double>& sigmas,
                       uint64_t seed, T* points);

// n points uniform in the box [lo, hi] (n x 3 out).
template <class T>
void sampleVolume(size_t n, Vec3d lo, Vec3d hi, uint64_t seed, T* points);

// DeepSDF's widths (standard deviations 0.05 and 0.0158 for a mesh in the unit sphere) scaled to
// the mesh: times half its bounding box's diagonal.
std::vector<double> defaultNearSurfaceSigmas(const MeshQuery& mesh);

}  // namespace sdft
