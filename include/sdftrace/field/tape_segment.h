// Galin, Guérin, Paris, Peytavie, "Segment Tracing Using Local Lipschitz Bounds" (Eurographics
// 2020), §4-5: the field at a point p and a bound on how fast it can change along the segment
// p + s u, s in [0, length], ahead of a ray. A sphere tracer may then step |f| / slope instead of
// |f| / L (trace/sphere_tracer.h, TraceOptions::segmentTracing): the slope of an exact distance
// along a ray is the cosine of its angle to the surface's normal, far under the global bound L
// along grazing rays, so a ray creeping along a floor or a wall takes a few long steps.
//
// The bound is composed per instruction, like the value:
// - primitives: the directional derivative's bound over the segment, exact for spheres, planes
//   and (rounded) boxes, the global bound (1 per unit of the point's speed) for the others;
// - hard and smooth CSG: an operand that provably does not decide the result anywhere on the
//   segment (its values, f ± slope·length, stay on the far side of the other's, by more than the
//   blend radius for smooth ops) is dropped; otherwise the larger slope (the polynomial smooth
//   minimum's gradient is a convex combination of its operands');
// - point transforms move the segment's direction with the point (rotation, scale); domain
//   repetition folds the segment, so below it every primitive takes the global bound;
// - bounds culling (decision 0002) skips what the point evaluator skips, so the value is the
//   point evaluator's; the segment then ends where a skipped operand's box could come nearer than
//   the running minimum (a bound valid on a segment holds on any part of it).
// The scalar evaluator of the CPU and the device alike (header code, like tape_view.h).
#pragma once

#include <cmath>

#include "sdftrace/field/tape_view.h"

namespace sdft {

struct SegmentBound {
    float value = 0;   // f(p)
    float slope = 0;   // |f(p + s u) - f(p + s' u)| <= slope |s - s'| for s, s' in [0, length]
    float length = 0;  // the segment the slope holds on (the asked one, clipped to p's cell)
};

namespace segment_ops {

// The largest segment asked: long enough for any scene, short enough that products of it with
// directions and slopes stay finite.
inline constexpr float kMaxLength = 1e30f;

// |d/ds (|q + s w| - r)| over s in [0, len]: with x the coordinate along w and h the distance of
// the line from the centre, the derivative is |w| x / sqrt(x^2 + h^2), largest in magnitude at the
// end of the segment farther from the foot of the perpendicular.
SDFT_HOST_DEVICE inline float sphereSlope(Vec3 q, Vec3 w, float len) {
    // Branch-free (the batch form vectorizes it): w = 0 or x = 0 give 0.
    const float wl = std::sqrt(dot(w, w));
    const float x0 = dot(q, w) / maxf(wl, 1e-30f);
    const float h2 = maxf(dot(q, q) - x0 * x0, 0.0f);
    const float x = maxf(std::fabs(x0), std::fabs(x0 + len * wl));
    const float r = h2 / maxf(x, 1e-30f) / maxf(x, 1e-30f);  // no overflow for a long segment
    return x > 0 ? wl / std::sqrt(1.0f + r) : 0.0f;
}

// The exterior of a box of half-size b (a rounded box: its inner box): the gradient is the unit
// vector from the nearest point of the box, whose components vanish on every axis along which the
// point lies within the box's slab. Where the segment's box stays outside the box, only the axes
// on which the segment leaves the slab count: the slope is the length of w on those axes.
SDFT_HOST_DEVICE inline float boxSlope(Vec3 q, Vec3 w, float len, Vec3 b) {
    const Vec3 e = q + w * len;
    const Vec3 lo = min(q, e), hi = max(q, e);
    bool touches = true;
    float active = 0;
    for (int a = 0; a < 3; ++a) {
        touches = touches && lo[a] <= b[a] && hi[a] >= -b[a];
        if (maxf(std::fabs(lo[a]), std::fabs(hi[a])) > b[a]) active += w[a] * w[a];
    }
    return touches ? length(w) : std::sqrt(active);
}

// A primitive's slope along the straight segment q + s w of its own frame; speed = |w|.
SDFT_HOST_DEVICE inline float primitiveSlope(Op op, Vec3 q, Vec3 w, float speed, float len,
                                             const float* k) {
    switch (op) {
        case Op::Sphere:
            return sphereSlope(q, w, len);
        case Op::Plane:
            return std::fabs(k[0] * w.x + k[1] * w.y + k[2] * w.z);
        case Op::Box:
            return boxSlope(q, w, len, Vec3(k[0], k[1], k[2]));
        case Op::RoundBox:
            return boxSlope(q, w, len, Vec3(k[0] - k[3], k[1] - k[3], k[2] - k[3]));
        default:
            return speed;  // every primitive is 1-Lipschitz
    }
}

// The slope of a binary op's result, from its operands' values at the segment's start and
// slopes over it.
SDFT_HOST_DEVICE inline float combineSlope(Op op, float a, float la, float b, float lb, float len,
                                           const float* k) {
    const float ra = la * len, rb = lb * len;  // each operand stays within value ± r
    const bool smooth =
        op == Op::SmoothUnion || op == Op::SmoothIntersection || op == Op::SmoothDifference;
    const float gap = smooth && k[0] > 0 ? k[0] : 0.0f;  // the smooth ops are exact beyond it
    const float both = maxf(la, lb);
    if (op == Op::Difference || op == Op::SmoothDifference) b = -b;  // max(a, -b)
    // Whether a stays above b over the segment by the gap, or b above a.
    const bool aAbove = a - ra - (b + rb) >= gap, bAbove = b - rb - (a + ra) >= gap;
    switch (op) {
        case Op::Union:
        case Op::SmoothUnion:  // the lower operand decides
            return aAbove ? lb : bAbove ? la : both;
        case Op::Intersection:
        case Op::SmoothIntersection:
        case Op::Difference:
        case Op::SmoothDifference:  // the higher one decides
            return bAbove ? lb : aAbove ? la : both;
        case Op::Morph:
            return std::fabs(1 - k[0]) * la + std::fabs(k[0]) * lb;
        default:
            return both;
    }
}

// A union operand that bounds culling skips at the segment's start (its box at least the running
// minimum acc plus the margin k[6] away) stays skipped while its box distance, falling at most at
// the point's speed, keeps that lead on acc, rising at most at its slope: the segment's length
// where that holds. A folded point (domain repetition) does not move straight, but everything
// below the fold takes the global bound, so its operands need no lead.
SDFT_HOST_DEVICE inline float cullClip(Vec3 p, float speed, bool straight, float acc,
                                       float accSlope, float len, const float* k) {
    const float lead = acc + k[6];
    if (!straight || lead <= 0) return len;  // lead <= 0: inside the running minimum
    const float dx = maxf(maxf(k[0] - p.x, p.x - k[3]), 0.0f);
    const float dy = maxf(maxf(k[1] - p.y, p.y - k[4]), 0.0f);
    const float dz = maxf(maxf(k[2] - p.z, p.z - k[5]), 0.0f);
    const float gap = std::sqrt(dx * dx + dy * dy + dz * dz) - lead;
    const float closing = accSlope + speed;
    return closing > 0 ? minf(len, maxf(gap, 0.0f) / closing) : len;
}

// The distance along u from p to where p's pruned cell ends (TapeCells: its tape holds only
// inside it); infinite where the outside or the whole tape evaluates p, which hold everywhere.
SDFT_HOST_DEVICE inline float cellExit(const TapeCells& c, Vec3 p, Vec3 u) {
    if (!c.instrs) return kInfinity;
    float exit = kInfinity;
    for (int a = 0; a < 3; ++a) {
        const float f = (p[a] - c.lo[a]) * c.invCell[a];
        if (!(f >= 0 && f <= static_cast<float>(c.res[a]))) return kInfinity;
        const int i = static_cast<int>(f) - (static_cast<int>(f) == c.res[a]);  // as tapeOf
        if (u[a] != 0) {
            const float face = c.lo[a] + static_cast<float>(u[a] > 0 ? i + 1 : i) / c.invCell[a];
            exit = minf(exit, maxf((face - p[a]) / u[a], 0.0f));
        }
    }
    return exit;
}

}  // namespace segment_ops

// The field at p and its slope along p + s u, s in [0, length] (u a unit direction), through
// the tape that evaluates p (its pruned cell's, clipped to the cell).
SDFT_HOST_DEVICE inline SegmentBound evalTapeSegment(const TapeView& t, Vec3 p, Vec3 u, float len) {
    using namespace segment_ops;
    float s[kTapeMaxScalarRegs], sl[kTapeMaxScalarRegs];
    Vec3 pts[kTapeMaxPointRegs], vel[kTapeMaxPointRegs];
    bool straight[kTapeMaxPointRegs];
    // Each point register's speed |w| when known without a square root (1 for the ray's own
    // point moved by translations, rotations and folds; scaled by uniform scales); < 0: compute.
    float speeds[kTapeMaxPointRegs];
    speeds[0] = 1;
    auto speed = [&](int r) { return speeds[r] >= 0 ? speeds[r] : length(vel[r]); };
    len = minf(minf(maxf(len, 0.0f), kMaxLength), cellExit(t.cells, p, u));
    pts[0] = p;
    vel[0] = u;
    straight[0] = true;
    TapeWalk walk = t.walkAt(p);
    for (uint32_t pc = 0; const Instr* next = walk.at(pc); ++pc) {
        const Instr& in = *next;
        const float* k = t.consts + in.k;
        const Op op = in.op;
        if (op == Op::CullIfFar) {
            if (tape_ops::cullSkips(pts[in.a], s[in.b], k)) {
                len = cullClip(pts[in.a], speed(in.a), straight[in.a], s[in.b], sl[in.b], len, k);
                pc = in.jump - 1;
            }
            continue;
        }
        if (op <= Op::Grid) {
            if (op == Op::Grid) {
                s[in.out] = tape_ops::gridValue(t.grids[static_cast<size_t>(k[0])], pts[in.a]);
                sl[in.out] = speed(in.a);
            } else {
                s[in.out] = tape_ops::primitive(op, pts[in.a], k);
                sl[in.out] = straight[in.a]
                                 ? primitiveSlope(op, pts[in.a], vel[in.a], speed(in.a), len, k)
                                 : speed(in.a);
            }
        } else if (op <= Op::Morph) {
            float h;
            sl[in.out] = combineSlope(op, s[in.a], sl[in.a], s[in.b], sl[in.b], len, k);
            s[in.out] = tape_ops::binary(op, s[in.a], s[in.b], k, h);
        } else if (op == Op::Complement) {
            s[in.out] = -s[in.a];
            sl[in.out] = sl[in.a];
        } else if (op == Op::Copy) {
            s[in.out] = s[in.a];
            sl[in.out] = sl[in.a];
        } else if (op == Op::ScaleValue) {
            s[in.out] = s[in.a] * k[0];
            sl[in.out] = sl[in.a] * std::fabs(k[0]);
        } else if (op == Op::RepeatBound || op == Op::FloorByBounds) {
            s[in.out] = op == Op::RepeatBound
                            ? minf(s[in.a], xform::repeatNeighbourBound(pts[in.b], k))
                            : xform::floorByBounds(s[in.a], pts[in.b], k);
            sl[in.out] = maxf(sl[in.a], speed(in.b));  // the bound is 1-Lipschitz
        } else if (op == Op::Displace) {
            s[in.out] = s[in.a] + tape_ops::displacement(pts[in.b], k);
            sl[in.out] = sl[in.a] + noise::fbmLipschitz(k[0], k[1], static_cast<int>(k[2]), k[3]) *
                                        speed(in.b);
        } else {
            pts[in.out] = tape_ops::pointOp(op, pts[in.a], k);
            // A rotation and a scale move the direction as they move points (neither translates).
            vel[in.out] = op == Op::Rotate || op == Op::ScalePoint
                              ? tape_ops::pointOp(op, vel[in.a], k)
                              : vel[in.a];
            straight[in.out] = straight[in.a] && op != Op::RepeatPoint;
            speeds[in.out] = op != Op::ScalePoint ? speeds[in.a]
                             : k[0] == k[1] && k[1] == k[2] && speeds[in.a] >= 0
                                 ? speeds[in.a] / std::fabs(k[0])
                                 : -1.0f;
        }
    }
    return {s[t.result], sl[t.result], len};
}

}  // namespace sdft
