#include "sdftrace/field/tape_segment_batch.h"

#include <algorithm>
#include <cmath>

#include "sdftrace/core/macros.h"
#include "sdftrace/exec/simd.h"
#include "sdftrace/field/lane_groups.h"
#include "sdftrace/field/tape_segment.h"

namespace sdft {

namespace {

constexpr int W = Tape::kBatchWidth;

// One group of lanes evaluated by one tape (the whole one or a cell's).
struct Group {
    const float *x, *y, *z, *ux, *uy, *uz;
    float *len, *value, *slope;  // len: bounds culling may shorten it
    int n;
};

// The register files of a group, W lanes per register.
struct Registers {
    float *points, *velocities, *scalars, *slopes;
    uint8_t* culled;
    float* culledLen;  // per cull slot, the segments of the lanes that skipped the operand
    // Per point register, the speed of its point as s runs, when the same on every lane (1 for
    // the ray's own point, moved by translations, rotations and repetition); < 0: per lane.
    float* speeds;
    float* p(int r, int axis) const { return points + (r * 3 + axis) * W; }
    float* v(int r, int axis) const { return velocities + (r * 3 + axis) * W; }
    float* s(int r) const { return scalars + r * W; }
    float* sl(int r) const { return slopes + r * W; }
    float speed(int r, int l) const {
        if (speeds[r] >= 0) return speeds[r];
        const float a = v(r, 0)[l], b = v(r, 1)[l], c = v(r, 2)[l];
        return std::sqrt(a * a + b * b + c * c);
    }
    Vec3 point(int r, int l) const { return {p(r, 0)[l], p(r, 1)[l], p(r, 2)[l]}; }
    Vec3 velocity(int r, int l) const { return {v(r, 0)[l], v(r, 1)[l], v(r, 2)[l]}; }
};

// A primitive's slopes along its lanes' segments (segment_ops::primitiveSlope, the switch
// outside the loop).
SDFT_HOT_INLINE void primitiveSlopes(const Registers& r, const Instr& in, bool straight,
                                     const float* k, const Group& g) {
    float* o = r.sl(in.out);
    const int a = in.a;
    if (!straight) {
        for (int l = 0; l < g.n; ++l) o[l] = r.speed(a, l);
        return;
    }
    switch (in.op) {
        case Op::Sphere:
            for (int l = 0; l < g.n; ++l)
                o[l] = segment_ops::sphereSlope(r.point(a, l), r.velocity(a, l), g.len[l]);
            break;
        case Op::Plane:
            for (int l = 0; l < g.n; ++l)
                o[l] = std::fabs(k[0] * r.v(a, 0)[l] + k[1] * r.v(a, 1)[l] + k[2] * r.v(a, 2)[l]);
            break;
        case Op::Box:
        case Op::RoundBox: {
            const float round = in.op == Op::RoundBox ? k[3] : 0.0f;
            const Vec3 half(k[0] - round, k[1] - round, k[2] - round);
            for (int l = 0; l < g.n; ++l)
                o[l] = segment_ops::boxSlope(r.point(a, l), r.velocity(a, l), g.len[l], half);
            break;
        }
        default:
            for (int l = 0; l < g.n; ++l) o[l] = r.speed(a, l);
    }
}

// Bounds culling as Tape::evalBatch does it; the lanes that skip end their segments where the
// operand could matter (segment_ops::cullClip). True when every lane skips. Unless every lane
// skips, the operand still runs on all of them; the guards inside it must not shorten the
// segments of lanes that skipped it (the scalar evaluator never runs them), so the operand's union
// puts those back.
SDFT_HOT_INLINE bool cullLanes(const Registers& r, const Instr& in, bool straight, const float* k,
                               const Group& g) {
    uint8_t* mask = r.culled + static_cast<size_t>(in.cull) * W;
    float* saved = r.culledLen + static_cast<size_t>(in.cull) * W;
    const float *acc = r.s(in.b), *accSlope = r.sl(in.b);
    int skipped = 0;
    for (int l = 0; l < g.n; ++l) {
        const Vec3 p = r.point(in.a, l);
        const bool skip = tape_ops::cullSkips(p, acc[l], k);
        if (skip)
            g.len[l] = segment_ops::cullClip(p, r.speed(in.a, l), straight, acc[l], accSlope[l],
                                             g.len[l], k);
        saved[l] = g.len[l];
        mask[l] = skip;
        skipped += skip;
    }
    return skipped == g.n;
}

// Union ... Morph: values as tape_ops::binary, slopes as segment_ops::combineSlope; a culled
// operand's lanes keep the accumulator and get back the segment its guard left them.
SDFT_HOT_INLINE void combine(const Registers& r, const Instr& in, const float* k, const Group& g) {
    float *o = r.s(in.out), *os = r.sl(in.out);
    const float *a = r.s(in.a), *sa = r.sl(in.a), *b = r.s(in.b), *sb = r.sl(in.b);
    const uint8_t* mask = in.cull >= 0 ? r.culled + static_cast<size_t>(in.cull) * W : nullptr;
    const float* saved = in.cull >= 0 ? r.culledLen + static_cast<size_t>(in.cull) * W : nullptr;
    float h;
    for (int l = 0; l < g.n; ++l) {
        if (mask && mask[l]) {
            o[l] = a[l], os[l] = sa[l];
            g.len[l] = saved[l];
        } else {
            os[l] = segment_ops::combineSlope(in.op, a[l], sa[l], b[l], sb[l], g.len[l], k);
            o[l] = tape_ops::binary(in.op, a[l], b[l], k, h);
        }
    }
}

// The other scalar instructions: values as Tape::evalBatch computes them, slopes as
// evalTapeSegment does.
SDFT_HOT_INLINE void scalarOp(const Registers& r, const Instr& in, const float* k, const Group& g) {
    float *o = r.s(in.out), *os = r.sl(in.out);
    const float *a = r.s(in.a), *sa = r.sl(in.a);
    switch (in.op) {
        case Op::Complement:
            for (int l = 0; l < g.n; ++l) o[l] = -a[l], os[l] = sa[l];
            break;
        case Op::Copy:
            for (int l = 0; l < g.n; ++l) o[l] = a[l], os[l] = sa[l];
            break;
        case Op::ScaleValue:
            for (int l = 0; l < g.n; ++l) o[l] = a[l] * k[0], os[l] = sa[l] * std::fabs(k[0]);
            break;
        case Op::RepeatBound:
        case Op::FloorByBounds:
            for (int l = 0; l < g.n; ++l) {
                const Vec3 q = r.point(in.b, l);
                o[l] = in.op == Op::RepeatBound ? minf(a[l], xform::repeatNeighbourBound(q, k))
                                                : xform::floorByBounds(a[l], q, k);
                os[l] = maxf(sa[l], r.speed(in.b, l));
            }
            break;
        case Op::Displace: {
            const float lip = noise::fbmLipschitz(k[0], k[1], static_cast<int>(k[2]), k[3]);
            for (int l = 0; l < g.n; ++l) {
                o[l] = a[l] + tape_ops::displacement(r.point(in.b, l), k);
                os[l] = sa[l] + lip * r.speed(in.b, l);
            }
            break;
        }
        default:  // Union ... Morph
            combine(r, in, k, g);
    }
}

SDFT_HOT_INLINE void pointOp(const Registers& r, const Instr& in, const float* k, const Group& g,
                             bool* straight) {
    for (int l = 0; l < g.n; ++l) {
        const Vec3 q = tape_ops::pointOp(in.op, r.point(in.a, l), k);
        const Vec3 w = in.op == Op::Rotate || in.op == Op::ScalePoint
                           ? tape_ops::pointOp(in.op, r.velocity(in.a, l), k)
                           : r.velocity(in.a, l);
        for (int axis = 0; axis < 3; ++axis) {
            r.p(in.out, axis)[l] = q[axis];
            r.v(in.out, axis)[l] = w[axis];
        }
    }
    straight[in.out] = straight[in.a] && in.op != Op::RepeatPoint;
    r.speeds[in.out] = in.op != Op::ScalePoint ? r.speeds[in.a]
                       : k[0] == k[1] && k[1] == k[2] && r.speeds[in.a] >= 0
                           ? r.speeds[in.a] / std::fabs(k[0])
                           : -1.0f;
}

SDFT_HOT_INLINE void evalGroup(const TapeView& view, const Instr* instrs, uint32_t count,
                               const Group& g, const Registers& r) {
    // Whether a point register moves on a straight line as s runs (the same on every lane).
    bool straight[kTapeMaxPointRegs];
    straight[0] = true;
    r.speeds[0] = 1;  // unit directions
    std::copy(g.x, g.x + g.n, r.p(0, 0));
    std::copy(g.y, g.y + g.n, r.p(0, 1));
    std::copy(g.z, g.z + g.n, r.p(0, 2));
    std::copy(g.ux, g.ux + g.n, r.v(0, 0));
    std::copy(g.uy, g.uy + g.n, r.v(0, 1));
    std::copy(g.uz, g.uz + g.n, r.v(0, 2));

#define SDFT_PRIMITIVE_SEGMENT_BATCH(Kind, name, eval, ...)             \
    case Op::Kind: {                                                    \
        float* o = r.s(in.out);                                         \
        for (int l = 0; l < g.n; ++l) o[l] = eval(r.point(in.a, l), k); \
        primitiveSlopes(r, in, straight[in.a], k, g);                   \
        break;                                                          \
    }

    TapeWalk walk(instrs, count, view.instrs);
    for (uint32_t pc = 0; const Instr* next = walk.at(pc); ++pc) {
        const Instr& in = *next;
        const float* k = view.consts + in.k;
        switch (in.op) {
            case Op::Run:  // TapeWalk follows it
                break;
            case Op::CullIfFar:
                if (cullLanes(r, in, straight[in.a], k, g)) pc = in.jump - 1;
                break;
                SDFT_PRIMITIVES(SDFT_PRIMITIVE_SEGMENT_BATCH)
            case Op::Grid: {
                const GridView& grid = view.grids[static_cast<size_t>(k[0])];
                for (int l = 0; l < g.n; ++l) {
                    r.s(in.out)[l] = tape_ops::gridValue(grid, r.point(in.a, l));
                    r.sl(in.out)[l] = r.speed(in.a, l);
                }
                break;
            }
            case Op::Translate:
            case Op::Rotate:
            case Op::ScalePoint:
            case Op::RepeatPoint:
                pointOp(r, in, k, g, straight);
                break;
            default:
                scalarOp(r, in, k, g);
        }
    }
#undef SDFT_PRIMITIVE_SEGMENT_BATCH
    std::copy(r.s(view.result), r.s(view.result) + g.n, g.value);
    std::copy(r.sl(view.result), r.sl(view.result) + g.n, g.slope);
}

// One chunk of at most W lanes: segments clipped to their cells, lanes grouped by their cell's
// tape (evalChunkByCell's grouping), each group evaluated by its tape.
SDFT_HOT_INLINE void evalChunk(const TapeView& view, const SegmentLanes& in, int start, int n,
                               SegmentBatchScratch& s, const Registers& r) {
    float* len = in.len + start;
    const Group all{in.x + start,  in.y + start, in.z + start,     in.ux + start,    in.uy + start,
                    in.uz + start, len,          in.value + start, in.slope + start, n};
    for (int l = 0; l < n; ++l) {
        const float asked = minf(maxf(len[l], 0.0f), segment_ops::kMaxLength);
        len[l] = minf(asked, segment_ops::cellExit(view.cells, Vec3(all.x[l], all.y[l], all.z[l]),
                                                   Vec3(all.ux[l], all.uy[l], all.uz[l])));
    }
    const Instr* first;
    uint32_t count;
    if (!view.cells.instrs) {
        evalGroup(view, view.instrs, view.count, all, r);
        return;
    }
    uint32_t* laneTape = s.laneTape.data();
    bool same = true;
    for (int l = 0; l < n; ++l) {
        laneTape[l] = view.cells.tapeOf(Vec3(all.x[l], all.y[l], all.z[l]));
        same &= laneTape[l] == laneTape[0];
    }
    if (same) {
        view.tapeSpan(laneTape[0], first, count);
        evalGroup(view, first, count, all, r);
        return;
    }
    uint32_t* order = s.order.data();
    float* gathered = s.gathered.data();
    const float* inputs[7] = {all.x, all.y, all.z, all.ux, all.uy, all.uz, all.len};
    for (int from = 0; from < n; ++from) {
        uint32_t t;
        const int m = takeLaneGroup(laneTape, from, n, order, t);
        if (m == 0) continue;
        for (int i = 0; i < m; ++i)
            for (int c = 0; c < 7; ++c) gathered[c * W + i] = inputs[c][order[i]];
        const Group group{gathered,         gathered + W,
                          gathered + 2 * W, gathered + 3 * W,
                          gathered + 4 * W, gathered + 5 * W,
                          gathered + 6 * W, gathered + 7 * W,
                          gathered + 8 * W, m};
        view.tapeSpan(t, first, count);
        evalGroup(view, first, count, group, r);
        for (int i = 0; i < m; ++i) {
            all.len[order[i]] = group.len[i];
            all.value[order[i]] = group.value[i];
            all.slope[order[i]] = group.slope[i];
        }
    }
}

void evalChunks(const TapeView& view, const SegmentLanes& lanes, int n, SegmentBatchScratch& s) {
    float speeds[kTapeMaxPointRegs];
    const Registers r{s.points.data(), s.velocities.data(), s.scalars.data(),
                      s.slopes.data(), s.culled.data(),     s.culledLen.data(),
                      speeds};
    for (int start = 0; start < n; start += W)
        evalChunk(view, lanes, start, std::min(W, n - start), s, r);
}

SDFT_TARGET_AVX2 void evalChunksAvx2(const TapeView& view, const SegmentLanes& lanes, int n,
                                     SegmentBatchScratch& s) {
    evalChunks(view, lanes, n, s);
}

SDFT_TARGET_BASELINE void evalChunksBaseline(const TapeView& view, const SegmentLanes& lanes, int n,
                                             SegmentBatchScratch& s) {
    evalChunks(view, lanes, n, s);
}

}  // namespace

void evalSegmentBatch(const Tape& tape, const SegmentLanes& lanes, int n, SegmentBatchScratch& s) {
    const TapeView view = tape.view();
    const size_t points = static_cast<size_t>(view.numPointRegs) * 3 * W;
    const size_t scalars = static_cast<size_t>(view.numScalarRegs) * W;
    for (auto* v : {&s.points, &s.velocities})
        if (v->size() < points) v->resize(points);
    for (auto* v : {&s.scalars, &s.slopes})
        if (v->size() < scalars) v->resize(scalars);
    const size_t culls = static_cast<size_t>(tape.numCulls()) * W;
    if (s.culled.size() < culls) {
        s.culled.resize(culls);
        s.culledLen.resize(culls);
    }
    if (s.gathered.size() < 9 * W) {
        s.gathered.resize(9 * W);
        s.laneTape.resize(W);
        s.order.resize(W);
    }
    if (useAvx2())
        evalChunksAvx2(view, lanes, n, s);
    else
        evalChunksBaseline(view, lanes, n, s);
}

}  // namespace sdft
