// Exact queries of a triangle mesh at arbitrary points: distances, closest points (face and
// barycentric coordinates), signed distances and inside/outside by three rules, generalized winding
// numbers and ray casts, in batches on all cores. The structures are built once (an Embree BVH at
// construction, the sign structures on first use) and every query is const and thread-safe.
//
// Precision: coordinates are kept relative to the mesh's bounding-box centre, the BVH search runs
// in float and the answer is recomputed in double on the triangle it found, so a distance is
// exact to double rounding up to ties between triangles within float rounding of each other
// (about 1e-7 of the mesh's extent).
//
// Signs (docs/guide/10-mesh-queries.md):
//  - Winding: the generalized winding number (Jacobson et al. 2013) of the mesh closed by its
//    films (bake/closing_film.h), > 1/2 inside. Exact on closed meshes; on scans with holes the
//    holes are spanned by the films, so the sign is the winding-number bake's.
//  - Parity: crossings of three rays, the majority's odd count; wrong where a ray leaves through
//    a hole.
//  - PseudoNormal: the angle-weighted pseudonormal of the closest feature (Baerentzen and Aanaes
//    2005): one traversal, exact on closed, manifold, consistently oriented meshes, arbitrary
//    elsewhere.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sdftrace/math/vec3d.h"

namespace sdft {

enum class MeshSign { Winding, Parity, PseudoNormal };
// "winding", "parity", "pseudonormal"; false for anything else.
bool parseMeshSign(const std::string& name, MeshSign& out);
inline constexpr const char* kMeshSigns = "winding, parity or pseudonormal";

class MeshQuery {
  public:
    // Faces index `vertices`; checked (InputError naming `what`): at least one face, indices in
    // range, coordinates finite. Faces are kept as given (face ids in answers index them); zero-
    // area faces count as their edges.
    MeshQuery(std::vector<Vec3d> vertices, std::vector<std::array<uint32_t, 3>> faces,
              const std::string& what = "mesh");
    ~MeshQuery();
    MeshQuery(const MeshQuery&) = delete;
    MeshQuery& operator=(const MeshQuery&) = delete;

    const std::vector<Vec3d>& vertices() const;
    const std::vector<std::array<uint32_t, 3>>& faces() const;
    // The mesh's bounding box (lo, hi) and the length of its diagonal.
    std::array<Vec3d, 2> bounds() const;
    double diagonal() const;
    // Whether every edge is shared by exactly two faces, once each way (closed and consistently
    // oriented, vertices welded by position).
    bool watertight() const;

    struct Closest {
        double distance = 0;
        Vec3d point;
        uint32_t face = 0;
        double bary[3] = {1, 0, 0};
        int feature = 0;  // triangle_closest.h: vertex, edge or face of `face`
    };
    Closest closest(Vec3d p) const;
    // With `bound` >= the distance at p (a neighbour's closest point's distance to p, say): the
    // same answer, faster for a tight bound.
    Closest closest(Vec3d p, double bound) const;

    double windingNumber(Vec3d p) const;
    // Inside by `sign`; `c` (the closest answer at p) is needed for PseudoNormal only.
    bool inside(Vec3d p, MeshSign sign, const Closest* c = nullptr) const;

    struct Hit {
        double t = INFINITY;  // in units of the direction's length; +inf: no hit within tMax
        uint32_t face = UINT32_MAX;
        double u = 0, v = 0;  // barycentrics of corners 1 and 2 (corner 0: 1 - u - v)
        Vec3d normal;         // the face's unit normal (counter-clockwise front)
    };
    Hit rayCast(Vec3d origin, Vec3d direction, double tMax = INFINITY) const;
    // refine: t and barycentrics recomputed in double on the hit face (else Embree's float ones).
    Hit rayCast(Vec3d origin, Vec3d direction, double tMax, bool refine) const;

    // Builds the sign structures for `sign` now (they are otherwise built on first use).
    void prepare(MeshSign sign) const;

    // Batches of n points (xyz interleaved, float or double): each output pointer may be null
    // (not wanted). Points are visited in chunks of a fixed size, in Morton order within a chunk:
    // clusters of 16 neighbours bound their distances by the previous cluster's faces, gather
    // their candidate faces in one BVH traversal and measure them eight at a time
    // (triangle_lanes.h), or search one by one where the candidates are many; on a closed mesh
    // the sign carries between neighbours, by the faces the segment between them crosses. Memory
    // beyond the outputs is bounded by the chunk, not by n. `progress` (may be empty) names a
    // progress line on stderr.
    struct PointOutputs {
        void* distance = nullptr;  // n, signed when `sign` is set
        void* closest = nullptr;   // n x 3
        int64_t* face = nullptr;   // n
        void* bary = nullptr;      // n x 3
        void* winding = nullptr;   // n
        bool* inside = nullptr;    // n
    };
    struct PointOptions {
        bool signedDistance = false;
        MeshSign sign = MeshSign::Winding;
        std::string progress;
    };
    template <class T>
    void queryPoints(const T* xyz, size_t n, const PointOutputs& out,
                     const PointOptions& options) const;

    struct RayOutputs {
        void* t = nullptr;        // n
        int64_t* face = nullptr;  // n (-1 on a miss)
        void* bary = nullptr;     // n x 2 (u, v)
        void* normal = nullptr;   // n x 3
    };
    template <class T>
    void castRays(const T* origins, const T* directions, size_t n, double tMax,
                  const RayOutputs& out, const std::string& progress = {}) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace sdft
