#include "sdftrace/bake/winding_packet.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "sdftrace/core/macros.h"
#include "sdftrace/exec/simd.h"

namespace sdft {

namespace {

constexpr int kLanes = 8;
constexpr double kFourPi = 12.566370614359172;  // a tree-less view sums 0: 0 / 4 pi

// x where `on`, else 0 (+0.0: adding it leaves a sum's bits as they are, but for the sign of a
// zero sum, which no comparison with 1/2 sees).
template <class Real>
inline Real masked(bool on, Real x) {
    return on ? x : Real(0);
}

// windingNumberFast of lanes `active` of p[0..kLanes) into sum (added), the scalar's traversal
// per lane: its stack order (left pushed before right), its far test, its dipole term and its
// float leaf sums.
// Real = float: the same traversal with the far terms in float (8 lanes to an AVX2 register, not
// 4), close to the double sum but not bit for bit.
template <class Real>
inline void packetSum(const WindingView& w, const Vec3* p, uint32_t active, double beta,
                      Real* sum) {
    using Mask = std::conditional_t<sizeof(Real) == 8, int64_t, int32_t>;
    if (w.nodeCount == 0 || active == 0) return;
    struct Entry {
        int node;
        uint32_t lanes;
    };
    Entry stack[128];
    int top = 0;
    stack[top++] = {0, active};
    Real px[kLanes], py[kLanes], pz[kLanes];
    for (int l = 0; l < kLanes; ++l) px[l] = p[l].x, py[l] = p[l].y, pz[l] = p[l].z;
    while (top > 0) {
        const Entry e = stack[--top];
        const WindingNode& n = w.nodes[e.node];
        const Real reach = static_cast<Real>(beta * beta * n.radius * n.radius);
        const Real cx = static_cast<Real>(n.cx), cy = static_cast<Real>(n.cy),
                   cz = static_cast<Real>(n.cz), nx = static_cast<Real>(n.nx),
                   ny = static_cast<Real>(n.ny), nz = static_cast<Real>(n.nz);
        Mask on[kLanes], nearLane[kLanes];
        for (int l = 0; l < kLanes; ++l) on[l] = (e.lanes >> l) & 1u;
        for (int l = 0; l < kLanes; ++l) {
            const Real dx = cx - px[l], dy = cy - py[l], dz = cz - pz[l];
            const Real d2 = dx * dx + dy * dy + dz * dz;
            const bool far = d2 > reach;
            // Far: the dipole term, Omega ~ (c - p).N / |c - p|^3 (Barill et al. 2018, eq. 8).
            const Real term = (dx * nx + dy * ny + dz * nz) / (d2 * std::sqrt(d2));
            sum[l] += on[l] && far ? term : Real(0);
            nearLane[l] = on[l] && !far;
        }
        uint32_t near = 0;
        for (int l = 0; l < kLanes; ++l) near |= static_cast<uint32_t>(nearLane[l]) << l;
        if (near == 0) continue;
        if (n.left < 0) {
            float leaf[kLanes] = {};
            for (int i = n.first; i < n.first + n.count; ++i) {
                const float* t = w.corners + 9 * static_cast<size_t>(i);
                for (int l = 0; l < kLanes; ++l) leaf[l] += solidAngleFloat(p[l], t);
            }
            for (int l = 0; l < kLanes; ++l)
                sum[l] += masked<Real>((near >> l) & 1u, static_cast<Real>(leaf[l]));
        } else if (top + 2 <= 128) {
            stack[top++] = {n.left, near};
            stack[top++] = {n.right, near};
        }
    }
}

// Up to kLanes points from p: the last ones repeat the last point (their answers unused).
inline void load(const Vec3* p, int n, Vec3* lanes) {
    for (int l = 0; l < kLanes; ++l) lanes[l] = p[std::min(l, n - 1)];
}

template <class Real>
inline void numberRow(const WindingView& w, const Vec3* p, int n, double beta, double* out,
                      uint64_t wanted) {
    for (int i = 0; i < n; i += kLanes) {
        const int m = std::min(kLanes, n - i);
        const uint32_t all = (1u << m) - 1;
        const uint32_t active = i < 64 ? static_cast<uint32_t>(wanted >> i) & all : all;
        if (active == 0) continue;
        Vec3 lanes[kLanes];
        load(p + i, m, lanes);
        Real sum[kLanes] = {};
        packetSum<Real>(w, lanes, active, beta, sum);
        for (int l = 0; l < m; ++l)
            if ((active >> l) & 1u) out[i + l] = static_cast<double>(sum[l]) / kFourPi;
    }
}

// windingInside per lane: the coarse beta (1.5) first, the full one for the lanes it leaves
// within 0.3 of 1/2.
inline void insideRow(const WindingView& w, const Vec3* p, int n, double beta, uint8_t* out) {
    for (int i = 0; i < n; i += kLanes) {
        const int m = std::min(kLanes, n - i);
        Vec3 lanes[kLanes];
        load(p + i, m, lanes);
        double coarse[kLanes] = {}, full[kLanes] = {};
        packetSum<double>(w, lanes, (1u << m) - 1, 1.5, coarse);
        uint32_t again = 0;
        for (int l = 0; l < m; ++l) {
            coarse[l] /= kFourPi;
            again |= static_cast<uint32_t>(std::fabs(coarse[l] - 0.5) <= 0.3) << l;
        }
        packetSum<double>(w, lanes, again, beta, full);
        for (int l = 0; l < m; ++l)
            out[i + l] = (again >> l) & 1u ? full[l] / kFourPi > 0.5 : coarse[l] > 0.5;
    }
}

SDFT_TARGET_AVX2 void insideRowAvx2(const WindingView& w, const Vec3* p, int n, double beta,
                                    uint8_t* out) {
    insideRow(w, p, n, beta, out);
}
SDFT_TARGET_BASELINE void insideRowBaseline(const WindingView& w, const Vec3* p, int n, double beta,
                                            uint8_t* out) {
    insideRow(w, p, n, beta, out);
}
template <class Real>
SDFT_TARGET_AVX2 void numberRowAvx2(const WindingView& w, const Vec3* p, int n, double beta,
                                    double* out, uint64_t wanted) {
    numberRow<Real>(w, p, n, beta, out, wanted);
}
template <class Real>
SDFT_TARGET_BASELINE void numberRowBaseline(const WindingView& w, const Vec3* p, int n, double beta,
                                            double* out, uint64_t wanted) {
    numberRow<Real>(w, p, n, beta, out, wanted);
}

}  // namespace

void windingInsideRow(const WindingView& w, const Vec3* p, int n, double beta, uint8_t* out) {
    (useAvx2() ? insideRowAvx2 : insideRowBaseline)(w, p, n, beta, out);
}

void windingNumberRow(const WindingView& w, const Vec3* p, int n, double beta, double* out,
                      uint64_t wanted) {
    (useAvx2() ? numberRowAvx2<double> : numberRowBaseline<double>)(w, p, n, beta, out, wanted);
}

void windingNumberRowFloat(const WindingView& w, const Vec3* p, int n, double beta, double* out,
                           uint64_t wanted) {
    (useAvx2() ? numberRowAvx2<float> : numberRowBaseline<float>)(w, p, n, beta, out, wanted);
}

}  // namespace sdft
