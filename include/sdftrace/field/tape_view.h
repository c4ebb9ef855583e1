// A compiled tape as plain data (docs/design.md "one plan, two devices"): pointers to its
// instructions, constants and grid views, trivially copyable, so a kernel takes it by value and
// the CPU's Tape hands out the same view of its own arrays. The scalar evaluators here are the
// only ones: Tape::eval and Tape::evalMaterial call them on the CPU, a device calls them per
// thread. The per-op functions are shared with the CPU's batch evaluator (field/tape_eval.cpp).
#pragma once

#include <cstdint>
#include <type_traits>

#include "sdftrace/core/macros.h"
#include "sdftrace/field/grid.h"
#include "sdftrace/field/grid_distance.h"
#include "sdftrace/field/material_blend.h"
#include "sdftrace/field/noise.h"
#include "sdftrace/field/operators.h"
#include "sdftrace/field/primitives.h"
#include "sdftrace/field/tape_instr.h"
#include "sdftrace/field/transforms.h"

namespace sdft {

// Hierarchical pruning (field/tape_prune.h): a lattice of cells over a box, each naming one of
// the pruned tapes, all back to back in `instrs` (spans[2 t], spans[2 t + 1]: first instruction
// and count of tape t). A point in a cell is evaluated by that cell's tape, which gives the whole
// tape's value there; a point outside the box by the outside tape, or the whole tape without one.
// Plain data, like the rest.
struct TapeCells {
    static constexpr uint32_t kWhole = ~0u;  // tapeOf: the whole tape

    const Instr* instrs = nullptr;  // null: no pruning
    const uint32_t* spans = nullptr;
    const uint32_t* cellTape = nullptr;  // per cell, x fastest
    int32_t outside = -1;                // the tape of points outside the box; -1: the whole tape
    int res[3] = {0, 0, 0};
    Vec3 lo;             // the box's low corner
    Vec3 invCell{0.0f};  // cells per unit length, per axis

    // The tape that evaluates p: an index into `spans`, or kWhole.
    SDFT_HOST_DEVICE uint32_t tapeOf(Vec3 p) const {
        const float fx = (p.x - lo.x) * invCell.x, fy = (p.y - lo.y) * invCell.y,
                    fz = (p.z - lo.z) * invCell.z;
        if (!(fx >= 0 && fy >= 0 && fz >= 0 && fx <= res[0] && fy <= res[1] && fz <= res[2]))
            return outside < 0 ? kWhole : static_cast<uint32_t>(outside);
        // fx == res[0] (the box's far face) belongs to the last cell.
        const int i = static_cast<int>(fx), j = static_cast<int>(fy), k = static_cast<int>(fz);
        return cellTape[((k - (k == res[2])) * res[1] + (j - (j == res[1]))) * res[0] +
                        (i - (i == res[0]))];
    }
};

// The instructions of a tape in the order they run: a pruned tape's Op::Run evaluates a stretch
// of the whole tape, then the tape goes on after it. A jump (CullIfFar) counts within the
// stretch it is in.
struct TapeWalk {
    // `tape` (count instructions) runs; its Runs read `whole`.
    SDFT_HOST_DEVICE TapeWalk(const Instr* tape, uint32_t count, const Instr* whole)
        : m_tape(tape), m_whole(whole), m_code(tape), m_count(count), m_end(count) {}
    // The instruction at pc, or null past the end; pc moves into and out of Runs.
    SDFT_HOST_DEVICE const Instr* at(uint32_t& pc) {
        for (;;) {
            if (pc >= m_end) {
                if (m_code == m_tape) return nullptr;
                m_code = m_tape, m_end = m_count, pc = m_resume + 1;
                continue;
            }
            const Instr& in = m_code[pc];
            if (in.op != Op::Run) return &in;
            m_resume = pc, m_code = m_whole, m_end = in.jump, pc = in.k;
        }
    }

  private:
    const Instr* m_tape;
    const Instr* m_whole;
    const Instr* m_code;  // the tape, or the whole tape inside a Run
    uint32_t m_count, m_end, m_resume = 0;
};

struct TapeView {
    const Instr* instrs = nullptr;
    const float* consts = nullptr;
    const GridView* grids = nullptr;  // Op::Grid's k[0] indexes this
    uint32_t count = 0;               // instructions
    uint16_t result = 0;              // the scalar register holding the value
    uint16_t numScalarRegs = 1;
    uint16_t numPointRegs = 1;
    float lipschitz = 1;
    Bounds3 bounds;
    TapeCells cells;

    // The instructions of tape t (TapeCells::tapeOf; kWhole: all of them).
    SDFT_HOST_DEVICE void tapeSpan(uint32_t t, const Instr*& first, uint32_t& n) const {
        if (t == TapeCells::kWhole) {
            first = instrs;
            n = count;
        } else {
            first = cells.instrs + cells.spans[2 * t];
            n = cells.spans[2 * t + 1];
        }
    }
    // The instructions that evaluate the field at p: its cell's pruned tape, or all of them.
    SDFT_HOST_DEVICE void tapeAt(Vec3 p, const Instr*& first, uint32_t& n) const {
        tapeSpan(cells.instrs ? cells.tapeOf(p) : TapeCells::kWhole, first, n);
    }
    // A walk of the instructions that evaluate the field at p (tapeAt).
    SDFT_HOST_DEVICE TapeWalk walkAt(Vec3 p) const {
        const Instr* first;
        uint32_t n;
        tapeAt(p, first, n);
        return TapeWalk(first, n, instrs);
    }
};
static_assert(std::is_trivially_copyable_v<TapeView>);

// The scalar evaluator's register files live on the stack; the tape compiler keeps every tape
// within these (deeper trees are rejected with an InputError).
inline constexpr int kTapeMaxScalarRegs = 64;
inline constexpr int kTapeMaxPointRegs = 32;

namespace tape_ops {

SDFT_HOST_DEVICE inline float primitive(Op op, Vec3 p, const float* k) {
    switch (op) {
#define SDFT_PRIMITIVE_EVAL(Kind, name, eval, ...) \
    case Op::Kind:                                 \
        return eval(p, k);
        SDFT_PRIMITIVES(SDFT_PRIMITIVE_EVAL)
#undef SDFT_PRIMITIVE_EVAL
        default:
            return 0;
    }
}

// Binary scalar ops. `h` returns the weight of `a` for material blending.
SDFT_HOST_DEVICE inline float binary(Op op, float a, float b, const float* k, float& h) {
    switch (op) {
        case Op::Union:
            h = a <= b ? 1.f : 0.f;
            return minf(a, b);
        case Op::Intersection:
            h = a >= b ? 1.f : 0.f;
            return maxf(a, b);
        case Op::Difference:
            h = a >= -b ? 1.f : 0.f;
            return maxf(a, -b);
        case Op::SmoothUnion:
            return ops::smoothMin(a, b, k[0], h);
        case Op::SmoothIntersection:
            return ops::smoothMax(a, b, k[0], h);
        case Op::SmoothDifference:
            return ops::smoothMax(a, -b, k[0], h);
        case Op::Morph:
            h = 1 - k[0];
            return (1 - k[0]) * a + k[0] * b;
        default:
            h = 1;
            return a;
    }
}

SDFT_HOST_DEVICE SDFT_HOT_INLINE Vec3 pointOp(Op op, Vec3 p, const float* k) {
    switch (op) {
        case Op::Translate:
            return p - Vec3(k[0], k[1], k[2]);
        case Op::Rotate:
            return {k[0] * p.x + k[1] * p.y + k[2] * p.z, k[3] * p.x + k[4] * p.y + k[5] * p.z,
                    k[6] * p.x + k[7] * p.y + k[8] * p.z};
        case Op::ScalePoint:
            return p / Vec3(k[0], k[1], k[2]);
        case Op::RepeatPoint:
            return xform::repeatPoint(p, k);
        default:
            return p;
    }
}

// CullIfFar's test, as the batch loop computes it: box distance >= acc + margin, squared.
SDFT_HOST_DEVICE inline bool cullSkips(Vec3 p, float acc, const float* k) {
    float dx = maxf(maxf(k[0] - p.x, p.x - k[3]), 0.0f);
    float dy = maxf(maxf(k[1] - p.y, p.y - k[4]), 0.0f);
    float dz = maxf(maxf(k[2] - p.z, p.z - k[5]), 0.0f);
    float t = acc + k[6];
    return (t <= 0.0f) | (dx * dx + dy * dy + dz * dz >= t * t);
}

SDFT_HOST_DEVICE inline float displacement(Vec3 p, const float* k) {
    return k[0] * noise::fbm(p * k[1], static_cast<int>(k[2]), k[3]);
}

// A grid's value, normalized by its Lipschitz bound so it is 1-Lipschitz like the primitives.
SDFT_HOST_DEVICE inline float gridValue(const GridView& g, Vec3 p) {
    return gridDistanceBound(g, p);
}

}  // namespace tape_ops

// The field at p and, with kMaterialRegs > 0, the material blend there. A material register per
// scalar register: kMaterialRegs must be at least the tape's numScalarRegs (the caller checks;
// a device build chooses a smaller file than the CPU's, since each entry is 120 bytes of stack).
template <int kMaterialRegs>
SDFT_HOST_DEVICE inline float evalTapeAt(const TapeView& t, Vec3 p, MaterialBlend* blend) {
    constexpr bool kMaterial = kMaterialRegs > 0;
    float s[kTapeMaxScalarRegs];
    Vec3 pts[kTapeMaxPointRegs];
    MaterialBlend mats[kMaterial ? kMaterialRegs : 1];
    pts[0] = p;
    TapeWalk walk = t.walkAt(p);
    for (uint32_t pc = 0; const Instr* next = walk.at(pc); ++pc) {
        const Instr& in = *next;
        const float* k = t.consts + in.k;
        const Op op = in.op;
        if (op == Op::CullIfFar) {
            if (tape_ops::cullSkips(pts[in.a], s[in.b], k)) pc = in.jump - 1;
            continue;
        }
        if (op <= Op::Grid) {
            s[in.out] = op == Op::Grid
                            ? tape_ops::gridValue(t.grids[static_cast<size_t>(k[0])], pts[in.a])
                            : tape_ops::primitive(op, pts[in.a], k);
            if constexpr (kMaterial) {
                mats[in.out] = MaterialBlend::single(in.material, pts[in.materialPoint]);
                if (op == Op::Grid) {
                    const GridView& g = t.grids[static_cast<size_t>(k[0])];
                    if (g.texcoords)
                        mats[in.out].hasUv[0] =
                            g.texcoordsAt(pts[in.a], mats[in.out].u[0], mats[in.out].v[0]);
                }
            }
        } else if (op <= Op::Morph) {
            float h;
            s[in.out] = tape_ops::binary(op, s[in.a], s[in.b], k, h);
            if constexpr (kMaterial)
                mats[in.out] = MaterialBlend::mix(mats[in.a], mats[in.b], 1 - h);
        } else if (op == Op::Complement) {
            s[in.out] = -s[in.a];
        } else if (op == Op::Copy) {
            s[in.out] = s[in.a];
            if constexpr (kMaterial) mats[in.out] = mats[in.a];
        } else if (op == Op::ScaleValue) {
            s[in.out] = s[in.a] * k[0];
        } else if (op == Op::RepeatBound) {
            s[in.out] = minf(s[in.a], xform::repeatNeighbourBound(pts[in.b], k));
        } else if (op == Op::FloorByBounds) {
            s[in.out] = xform::floorByBounds(s[in.a], pts[in.b], k);
        } else if (op == Op::Displace) {
            s[in.out] = s[in.a] + tape_ops::displacement(pts[in.b], k);
        } else {
            pts[in.out] = tape_ops::pointOp(op, pts[in.a], k);
        }
    }
    if constexpr (kMaterial) *blend = mats[t.result];
    return s[t.result];
}

// The field at p.
SDFT_HOST_DEVICE inline float evalTape(const TapeView& t, Vec3 p) {
    return evalTapeAt<0>(t, p, nullptr);
}

}  // namespace sdft
