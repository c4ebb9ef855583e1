// Shared by the dense and the narrow-band exact bakes (internal): vertex positions, the sign
// tests, and the thread arena size.
#pragma once

#include <tbb/task_arena.h>

#include <atomic>
#include <cmath>
#include <memory>

#include "sdftrace/bake/exact_bake.h"
#include "sdftrace/bake/winding_number.h"

namespace sdft::detail {

// Samples runs of vertices along +x with the row tricks of the header comment.
class RowSampler {
  public:
    RowSampler(const MeshBvh& bvh, const GridShape& shape, SignMethod sign)
        : m_bvh(bvh), m_shape(shape), m_watertight(isWatertight(bvh.mesh())) {
        if (sign == SignMethod::WindingNumber)
            m_winding = std::make_unique<WindingNumber>(bvh.mesh());
    }

    Vec3 position(int i, int j, int k) const {
        return m_shape.origin + Vec3(i, j, k) * m_shape.voxelSize;
    }

    bool watertight() const { return m_watertight; }

    bool inside(Vec3 p) const { return m_winding ? m_winding->inside(p) : m_bvh.insideByParity(p); }
    // The integer winding number of a watertight mesh at p: the hierarchical sum at the coarse
    // beta of WindingNumber::inside (trusted there to 0.3), rounded. Only with
    // SignMethod::WindingNumber.
    int windingAt(Vec3 p) const { return static_cast<int>(std::lround(m_winding->fast(p, 1.5))); }
    bool hasWinding() const { return m_winding != nullptr; }

    // Vertices (i0 + n', j, k), n' < n, into out[0, n).
    void row(int i0, int j, int k, int n, float* out, std::atomic<size_t>& queries,
             std::atomic<size_t>& signs) const {
        // 0.1% over the spacing: far above the rounding of the distances, so both the search
        // radius and the sign rule stay conservative.
        const float step = m_shape.voxelSize * 1.001f;
        float prev = INFINITY;
        Vec3 prevPoint;
        bool prevInside = false;
        size_t evaluated = 0;
        for (int n1 = 0; n1 < n; ++n1) {
            Vec3 p = position(i0 + n1, j, k);
            // The previous closest point bounds this distance (tighter than prev + h).
            MeshBvh::Closest c = prev == INFINITY
                                     ? m_bvh.closest(p)
                                     : m_bvh.closest(p, length(p - prevPoint) * 1.0001f + 1e-30f);
            if (c.distance == INFINITY) c = m_bvh.closest(p);  // unreachable but for rounding
            float d = c.distance;
            prevPoint = c.point;
            // Watertight: d > h means the ball around p holds no surface yet holds the previous
            // vertex, so no crossing lies between them.
            bool in;
            if (m_watertight && n1 > 0 && (d > step || prev > step)) {
                in = prevInside;
            } else {
                in = inside(p);
                ++evaluated;
            }
            out[n1] = in ? -d : d;
            prev = d;
            prevInside = in;
        }
        queries += n;
        signs += evaluated;
    }

  private:
    const MeshBvh& m_bvh;
    const GridShape& m_shape;
    bool m_watertight;
    std::unique_ptr<WindingNumber> m_winding;
};

inline int arenaThreads(int threads) {
    return threads > 0 ? threads : tbb::this_task_arena::max_concurrency();
}

inline void report(ExactBakeStats* stats, const std::atomic<size_t>& queries,
                   const std::atomic<size_t>& signs) {
    if (!stats) return;
    stats->distanceQueries = queries.load();
    stats->signEvaluations = signs.load();
}

}  // namespace sdft::detail
