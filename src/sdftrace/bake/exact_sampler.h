// Shared by the dense and the narrow-band exact bakes (internal): vertex positions, the sign
// tests, and the thread arena size.
#pragma once

#include <atomic>
#include <cmath>
#include <memory>

#include "sdftrace/bake/closing_film.h"
#include "sdftrace/bake/exact_bake.h"
#include "sdftrace/bake/segment_crossing.h"
#include "sdftrace/bake/winding_number.h"
#include "sdftrace/bake/winding_sign.h"

namespace sdft::detail {

// Samples runs of vertices along +x with the row tricks of the header comment.
class RowSampler {
  public:
    // `bvh` (closest points, parity) may be null for the narrow band's winding-number signs.
    // With `deferSigns` the winding-number tree is built by prepareSigns(), so that it does not
    // take memory while the distances are found.
    RowSampler(const TriangleMesh& mesh, const MeshBvh* bvh, const GridShape& shape,
               SignMethod sign, bool deferSigns = false)
        : m_bvh(bvh),
          m_shape(shape),
          m_useWinding(sign == SignMethod::WindingNumber),
          m_film(std::make_unique<ClosingFilm>(mesh)) {
        m_watertight = m_film->empty();
        if (!deferSigns) prepareSigns();
    }
    void prepareSigns() {
        if (m_useWinding && !m_winding)
            m_winding = std::make_unique<WindingNumber>(m_film->closedMesh());
    }

    Vec3 position(int i, int j, int k) const {
        return m_shape.origin + Vec3(i, j, k) * m_shape.voxelSize;
    }

    bool watertight() const { return m_watertight; }
    // Frees the films and the winding-number tree once no sign is left to decide.
    void releaseSigns() {
        m_winding.reset();
        m_film.reset();
    }
    // With SignMethod::WindingNumber: signs follow the integer winding number of the mesh closed
    // by its films (closing_film.h), carried between neighbours.
    bool hasWinding() const { return m_useWinding; }

    // The winding numbers carried from sample to sample (winding_sign.h).
    using Carried = WindingSign::Carried;

    // Whether p is inside: from the winding number, or by ray parity.
    bool inside(Vec3 p) const {
        return m_winding ? evaluate(p).inside() : m_bvh->insideByParity(p);
    }
    Carried evaluate(Vec3 p) const { return WindingSign(*m_film, *m_winding).evaluate(p); }
    Carried refresh(Vec3 p, int32_t closed) const {
        return WindingSign::refresh(*m_film, p, closed);
    }
    // From a neighbour's values across a segment with the given signed crossings (of mesh and
    // films, and of the mesh alone) along which w_M may drift by `drift`; summed over the films
    // again (counted in `refreshed`) where the sign is then unsure.
    Carried carry(const Carried& from, int crossings, int meshCrossings, float drift, Vec3 p,
                  size_t& refreshed) const {
        Carried c{from.closed + crossings, from.winding + static_cast<float>(meshCrossings),
                  from.error + drift};
        if (!c.decided()) {
            c = refresh(p, c.closed);
            ++refreshed;
        }
        return c;
    }
    // Bounds |grad w_M| over the box: a carried w_M changes by at most this times the step (0 on
    // a watertight mesh, where it is the integer W).
    float gradientBound(Vec3 lo, Vec3 hi) const {
        return m_film->empty() ? 0.0f : static_cast<float>(m_film->gradientBound(lo, hi));
    }
    // The film triangles whose bounds overlap the box grown by a hair.
    void filmsNear(Vec3 lo, Vec3 hi, std::vector<uint32_t>& out) const {
        out.clear();
        if (!m_film) return;
        const float eps = 1e-4f * m_shape.voxelSize;
        const auto& films = m_film->filmTriangles();
        for (size_t t = 0; t < films.size(); ++t) {
            const CrossingTriangle& f = films[t];
            if (f.lo.x <= hi.x + eps && f.lo.y <= hi.y + eps && f.lo.z <= hi.z + eps &&
                f.hi.x >= lo.x - eps && f.hi.y >= lo.y - eps && f.hi.z >= lo.z - eps)
                out.push_back(static_cast<uint32_t>(t));
        }
    }
    // The signed crossings of segment a -> b with the listed film triangles, added to `delta`:
    // false when one is undecided.
    bool filmCrossings(Vec3 a, Vec3 b, const std::vector<uint32_t>& near, int& delta) const {
        const float eps = 1e-5f * m_shape.voxelSize;
        for (uint32_t t : near) {
            Crossing c = segmentCrossing(a, b, m_film->filmTriangles()[t], eps);
            if (c == Crossing::Undecided) return false;
            delta += c == Crossing::Enter ? 1 : c == Crossing::Leave ? -1 : 0;
        }
        return true;
    }

    // Vertices (i0 + n', j, k), n' < n, into out[0, n). With `known` (may be `out`), their
    // distances are given (a non-finite one is queried) and only the signs are found.
    void row(int i0, int j, int k, int n, float* out, std::atomic<size_t>& queries,
             std::atomic<size_t>& signs, std::atomic<size_t>& filmSums,
             const float* known = nullptr) const {
        // 0.1% over the spacing: far above the rounding of the distances, so both the search
        // radius and the sign rule stay conservative.
        const float step = m_shape.voxelSize * 1.001f;
        float prev = INFINITY;
        Vec3 prevPoint;
        bool prevInside = false;
        Carried carried;
        float gradient = 0;
        size_t evaluated = 0, refreshed = 0, queried = 0;
        constexpr int kChunk = 8;  // vertices per gradient bound
        std::vector<uint32_t> films;
        if (m_winding) filmsNear(position(i0, j, k), position(i0 + n - 1, j, k), films);
        for (int n1 = 0; n1 < n; ++n1) {
            Vec3 p = position(i0 + n1, j, k);
            float d;
            if (known && std::isfinite(known[n1])) {
                d = known[n1];
                prevPoint = Vec3(INFINITY);  // no closest point to bound the next query by
            } else {
                // The previous closest point bounds this distance (tighter than prev + h).
                MeshBvh::Closest c =
                    prev == INFINITY || !std::isfinite(prevPoint.x)
                        ? m_bvh->closest(p)
                        : m_bvh->closest(p, length(p - prevPoint) * 1.0001f + 1e-30f);
                if (c.distance == INFINITY) c = m_bvh->closest(p);  // unreachable but rounding
                d = c.distance;
                prevPoint = c.point;
                ++queried;
            }
            // d > h means the ball around p holds no surface yet holds the previous vertex, so
            // the mesh is not crossed between them.
            const bool meshClear = n1 > 0 && (d > step || prev > step);
            bool in;
            if (m_winding) {
                if (n1 % kChunk == 0)
                    gradient = gradientBound(position(i0 + n1 - 1, j, k),
                                             position(std::min(i0 + n1 + kChunk, i0 + n), j, k));
                int delta = 0;
                if (meshClear && filmCrossings(position(i0 + n1 - 1, j, k), p, films, delta)) {
                    carried = carry(carried, delta, 0, gradient * m_shape.voxelSize, p, refreshed);
                } else {
                    carried = evaluate(p);
                    ++evaluated;
                }
                in = carried.inside();
            } else if (m_watertight && meshClear) {
                in = prevInside;
            } else {
                in = inside(p);
                ++evaluated;
            }
            out[n1] = in ? -d : d;
            prev = d;
            prevInside = in;
        }
        queries += queried;
        signs += evaluated;
        filmSums += refreshed;
    }

  private:
    const MeshBvh* m_bvh;
    const GridShape& m_shape;
    bool m_useWinding;
    bool m_watertight = false;
    std::unique_ptr<ClosingFilm> m_film;
    std::unique_ptr<WindingNumber> m_winding;
};

inline void report(ExactBakeStats* stats, const std::atomic<size_t>& queries,
                   const std::atomic<size_t>& signs, const std::atomic<size_t>& filmSums) {
    if (!stats) return;
    stats->filmSums = filmSums.load();
    stats->distanceQueries = queries.load();
    stats->signEvaluations = signs.load();
}

}  // namespace sdft::detail
