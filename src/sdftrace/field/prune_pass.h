// The pruning pass (tape_prune.h; Barbier et al., Eurographics 2025): interval bounds of every
// instruction of a node's tape over its (up to) eight children, from the value at each child's
// centre and the Lipschitz bound of the primitives (every primitive is 1-Lipschitz; a point
// transform scales that by its stretch), tighter for spheres and primitives that dominate their
// bounds, propagated through the CSG operators; folds drop the operands those bounds rule out,
// and emit writes the children's tapes. Internal to the pruning build.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <vector>

#include "sdftrace/exec/simd.h"
#include "sdftrace/field/prune_lanes.h"
#include "sdftrace/field/tape_view.h"

namespace sdft::prune {

// How far a point operator can move two points apart, per unit (infinite: not Lipschitz).
inline float stretch(Op op, const float* k) {
    switch (op) {
        case Op::Translate:
        case Op::Rotate:
            return 1;
        case Op::ScalePoint:
            return 1.0f / std::min({std::fabs(k[0]), std::fabs(k[1]), std::fabs(k[2])});
        default:
            return kInfinity;  // repetition folds space
    }
}

// A primitive's bounds in its frame where its value outside them is at least the distance to them
// (primitive_table.h's "dominates bounds"), else an empty box.
inline Bounds3 dominatedBounds(Op op, const float* k) {
    switch (op) {
#define SDFT_PRUNE_BOUNDS(Kind, name, eval, bounds, convex, dominates) \
    case Op::Kind:                                                     \
        return dominates ? bounds(k) : Bounds3{};
        SDFT_PRIMITIVES(SDFT_PRUNE_BOUNDS)
#undef SDFT_PRUNE_BOUNDS
        default:
            return Bounds3{};
    }
}

// The pruner's working memory, one per thread, reused from pass to pass (a build visits tens of
// thousands of cells; allocating per cell cost more than the pruning).
struct PruneScratch {
    struct Chain {
        Op op;
        int32_t first, front;  // the fold's first operand, its first member
        bool valid;
        LaneMask replaceFirst;
        F8 best;  // the best bound an operand guarantees
    };
    std::vector<LaneInterval> out;
    std::vector<int32_t> accDef, rhsDef, chainOf;
    std::vector<Chain> chains;
    std::vector<int32_t> hard;   // the hard folds' members, in order
    std::vector<uint32_t> next;  // emit's renumbering
};

// A tape pruned for the points of each of up to kLanes cells of one size: each fold operand
// whose value over the cell, bounded by its value at the cell's centre and the Lipschitz bound
// of its subtree, can never be the one that decides the fold is removed (hard union,
// intersection and difference), or whose blend weight is zero over the cell (smooth union,
// intersection and difference: |a - b| >= k). The result equals the tape's at every point of the
// cell (up to one rounding of a smooth blend's a + (b - a) at weight 1). Operands under a grid, a
// repetition or a displacement are kept.
class Pruner {
  public:
    // `local`: per instruction of the whole tape, dominatedBounds'.
    Pruner(const FlatTape& t, const float* consts, const Bounds3* local, const Bounds3* cells,
           int n, PruneScratch& s, PruneResult& r)
        : m_t(t), m_k(consts), m_local(local), m_n(t.instrs.size()), m_s(s), m_r(r) {
        SDFT_CHECK(n >= 1 && n <= kLanes);
        for (int l = 0; l < kLanes; ++l) {  // spare lanes repeat the first cell
            const Bounds3& cell = cells[l < n ? l : 0];
            m_centre[l] = (cell.lo + cell.hi) * 0.5f;
            m_radius[l] = 0.5f * length(cell.hi - cell.lo);
            m_half[0][l] = 0.5f * (cell.hi.x - cell.lo.x);
            m_half[1][l] = 0.5f * (cell.hi.y - cell.lo.y);
            m_half[2][l] = 0.5f * (cell.hi.z - cell.lo.z);
        }
        m_lanes = static_cast<LaneMask>((1u << n) - 1);
        // accDef, rhsDef and chainOf are read only where bounds() wrote them (folds).
        m_s.out.resize(m_n);
        m_s.accDef.resize(m_n);
        m_s.rhsDef.resize(m_n);
        m_s.chainOf.resize(m_n);
        m_s.chains.clear();
        m_s.hard.clear();
        m_r.drop.assign(m_n, 0);
        m_r.copy.assign(m_n, 0);
        m_r.changed = 0;
        m_r.copied = 0;
    }
    // Bounds every instruction over the cells and decides what each drops (into the result).
    void run() {
        if (useAvx2())
            runAvx2();
        else
            runBaseline();
        m_r.changed &= m_lanes;
    }

    // How many instructions each lane keeps.
    static void countKept(const PruneResult& r, uint32_t count[kLanes]) {
        // Eight instructions' masks to a word; per lane, a byte of a word counts its drops (at
        // most 255 words before the bytes are summed).
        constexpr uint64_t kOnes = 0x0101010101010101ull;
        const size_t n = r.drop.size();
        uint64_t dropped[kLanes] = {};
        for (size_t i = 0; i < n;) {
            uint64_t acc[kLanes] = {};
            for (int w = 0; w < 255 && i + 8 <= n; ++w, i += 8) {
                uint64_t word;
                std::memcpy(&word, r.drop.data() + i, 8);
                for (int l = 0; l < kLanes; ++l) acc[l] += (word >> l) & kOnes;
            }
            constexpr uint64_t kBytes = 0x00FF00FF00FF00FFull, kShorts = 0x0001000100010001ull;
            for (int l = 0; l < kLanes; ++l) {  // the bytes summed in 16-bit fields, then all
                const uint64_t pairs = (acc[l] & kBytes) + ((acc[l] >> 8) & kBytes);
                dropped[l] += (pairs * kShorts) >> 48;
            }
            if (i + 8 > n) {
                for (; i < n; ++i)
                    for (int l = 0; l < kLanes; ++l) dropped[l] += (r.drop[i] >> l) & 1;
            }
        }
        for (int l = 0; l < kLanes; ++l) count[l] = static_cast<uint32_t>(n - dropped[l]);
    }

    // One pass over the tape (`kept`: countKept's): the pruned tapes of the lanes in `full`, into
    // out[l] (the kept instructions, renumbered: jumps, fold records, copies), and for them and
    // those in `counted`, `next`: per instruction i and lane, the lane's index of its first kept
    // instruction >= i (LaneCompactor reads the counted ones).
    struct Emit {
        const FlatTape& t;
        const PruneResult& r;
        const uint32_t* kept;
        LaneMask full;
        FlatTape* const* out;
        LaneMask counted;
        std::vector<uint32_t>& next;
    };
    // Built twice like the pass (exec/simd.h).
    static void emit(const Emit& e) {
        if (useAvx2())
            emitAvx2(e);
        else
            emitBaseline(e);
    }

  private:
    SDFT_TARGET_AVX2 static void emitAvx2(const Emit& e) { emitPass(e); }
    SDFT_TARGET_BASELINE static void emitBaseline(const Emit& e) { emitPass(e); }
    static void emitPass(const Emit& e) {
        const FlatTape& t = e.t;
        const PruneResult& r = e.r;
        const uint32_t* kept = e.kept;
        const LaneMask full = e.full;
        FlatTape* const* out = e.out;
        std::vector<uint32_t>& next = e.next;
        const size_t n = t.instrs.size();
        for (int l = 0; l < kLanes; ++l) {
            if (full >> l & 1) {
                out[l]->instrs.resize(kept[l]);
                out[l]->folds.resize(kept[l]);
                out[l]->origin.resize(kept[l]);
                out[l]->made = (r.copied >> l & 1) || t.made;
            }
        }
        // Each lane's count of kept instructions so far, in vector registers: stored to `next`
        // whole, it would have stalled on the increments' partial stores from memory.
        const I8 laneBit = {1, 2, 4, 8, 16, 32, 64, 128};
        I8 pos = {};
        next.resize((n + 1) * kLanes);
        const unsigned lanes = full | e.counted;
        for (size_t i = 0; i < n; ++i) {
            std::memcpy(next.data() + i * kLanes, &pos, sizeof pos);
            const unsigned keep = ~r.drop[i] & lanes;
            if (!keep) continue;
            const I8 at = pos;
            pos -= (laneBit & static_cast<int32_t>(keep)) == laneBit;  // true is -1
            const Instr& in = t.instrs[i];
            const bool combine = isCombine(in.op);
            for (unsigned write = keep & full; write; write &= write - 1) {
                const int l = std::countr_zero(write);
                const auto j = static_cast<uint32_t>(at[l]);
                FlatTape& o = *out[l];
                const bool copy = r.copy[i] >> l & 1;
                o.instrs[j] = copy ? copyOf(in) : in;
                o.folds[j] = {};
                o.origin[j] = copy ? FlatTape::kMade : t.origin[i];
                if (!copy && combine) {  // fold records point back
                    o.folds[j] = {next[t.folds[i].operand * kLanes + l],
                                  next[t.folds[i].fold * kLanes + l]};
                }
            }
        }
        std::memcpy(next.data() + n * kLanes, &pos, sizeof pos);
        for (int l = 0; l < kLanes; ++l) {  // guards jump forward, past their (kept) operator
            if (!(full >> l & 1)) continue;
            for (Instr& in : out[l]->instrs)
                if (in.op == Op::CullIfFar) in.jump = laneJump(next.data(), in.jump, l);
        }
    }

    // The pass built twice (exec/simd.h): eight lanes are one AVX2 register.
    SDFT_TARGET_AVX2 void runAvx2() {
        bounds();
        decideHard();
    }
    SDFT_TARGET_BASELINE void runBaseline() {
        bounds();
        decideHard();
    }

    // Forward pass: every scalar instruction's interval over each cell; smooth folds decided
    // and hard ones gathered into chains on the way.
    void bounds() {
        F8 px[kTapeMaxPointRegs], py[kTapeMaxPointRegs], pz[kTapeMaxPointRegs],
            ps[kTapeMaxPointRegs];
        // A scalar register's interval is its writer's (no copies: the intervals are a
        // vector register pair each, and copying them member by member stalled the loads that
        // followed on their partial stores).
        const LaneInterval unknown{splat(-kInfinity), splat(kInfinity)};
        const LaneInterval* sr[kTapeMaxScalarRegs];
        std::fill_n(sr, kTapeMaxScalarRegs, &unknown);
        int32_t writer[kTapeMaxScalarRegs];
        std::fill_n(writer, kTapeMaxScalarRegs, -1);
        // Whether a point register is the cell's point only translated: its cells are boxes of
        // the cells' extents about px, py, pz.
        bool boxed[kTapeMaxPointRegs] = {true};
        for (int l = 0; l < kLanes; ++l) {
            px[0][l] = m_centre[l].x;
            py[0][l] = m_centre[l].y;
            pz[0][l] = m_centre[l].z;
        }
        ps[0] = splat(1);
        const F8 inf = splat(kInfinity);
        int32_t last = -1;
        for (size_t i = 0; i < m_n; ++i) {
            const Instr& in = m_t.instrs[i];
            const float* k = m_k + in.k;
            const Op op = in.op;
            if (op == Op::CullIfFar) continue;
            LaneInterval& r = m_s.out[i];
            if (op < Op::Grid) {
                const F8 v = primitiveLanes(op, px[in.a], py[in.a], pz[in.a], k);
                const F8 reach = m_radius * ps[in.a];
                // A margin for the rounding of the centre's value and the radius.
                const F8 pad = 1e-5f * (vabs(v) + reach) + 1e-7f;
                const I8 known = (vabs(v) < inf) & (reach < inf);
                r.lo = known ? v - reach - pad : -inf;
                r.hi = known ? v + reach + pad : inf;
                if (boxed[in.a] && m_t.origin[i] != FlatTape::kMade)
                    tighten(op, px[in.a], py[in.a], pz[in.a], k, m_local[m_t.origin[i]], r);
            } else if (op >= Op::Translate && op <= Op::RepeatPoint) {  // a point operator
                boxed[in.out] = boxed[in.a] && op == Op::Translate;
                pointLanes(op, k, px[in.a], py[in.a], pz[in.a], px[in.out], py[in.out], pz[in.out]);
                const F8 x = px[in.out], y = py[in.out], z = pz[in.out];
                const I8 finite = (x - x == 0) & (y - y == 0) & (z - z == 0);
                ps[in.out] = finite ? ps[in.a] * stretch(op, k) : inf;
                continue;
            } else {
                if (op >= Op::Union && op <= Op::Morph) {
                    m_s.accDef[i] = writer[in.a];
                    m_s.rhsDef[i] = writer[in.b];
                }
                scalarLanes(op, *sr[in.a], *sr[in.b], k, r);
                if (isHardCombine(op))
                    joinChain(static_cast<int32_t>(i));
                else if (isCombine(op) && op != Op::Morph)
                    decideSmooth(static_cast<int32_t>(i));
            }
            r.lo = r.lo == r.lo ? r.lo : -inf;  // NaN: unknown
            r.hi = r.hi == r.hi ? r.hi : inf;
            if (writesScalar(op)) {
                sr[in.out] = &r;
                writer[in.out] = static_cast<int32_t>(i);
                last = static_cast<int32_t>(i);
            }
        }
        for (int l = 0; l < kLanes; ++l)
            m_r.value[l] =
                last < 0 ? Interval{} : Interval{m_s.out[last].lo[l], m_s.out[last].hi[l]};
    }

    // A primitive's values over the cells, tighter than the Lipschitz bound about their centres
    // where (x, y, z) are the cells' centres in the primitive's frame, the cells boxes of the same
    // extents there: a sphere's lie between the distances from its centre to the nearest and
    // farthest points of the cell; a primitive whose value outside its bounds is at least the
    // distance to them (`local`, the bounds; empty for the others) has values at least the gap
    // between the cell and its bounds where they do not meet.
    void tighten(Op op, const F8& x, const F8& y, const F8& z, const float* k, const Bounds3& local,
                 LaneInterval& r) const {
        const F8 zero{};
        const F8* h = m_half;
        if (op == Op::Sphere) {
            const F8 ax = vabs(x), ay = vabs(y), az = vabs(z);
            const F8 near =
                lengthLanes(vmax(ax - h[0], zero), vmax(ay - h[1], zero), vmax(az - h[2], zero));
            const F8 far = lengthLanes(ax + h[0], ay + h[1], az + h[2]);
            const F8 pad = 1e-5f * (far + k[0]) + 1e-7f;
            r.lo = vmax(r.lo, near - k[0] - pad);
            r.hi = vmin(r.hi, far - k[0] + pad);
            return;
        }
        if (local.empty()) return;
        auto apart = [&](const F8& c, const F8& half, int a) {  // along axis a, or 0
            return vmax(vmax(local.lo[a] - (c + half), (c - half) - local.hi[a]), zero);
        };
        const F8 gap = lengthLanes(apart(x, h[0], 0), apart(y, h[1], 1), apart(z, h[2], 2));
        const F8 pad = 1e-5f * (gap + vabs(x) + vabs(y) + vabs(z)) + 1e-7f;
        r.lo = gap > 0 ? vmax(r.lo, gap - pad) : r.lo;
    }
    static F8 lengthLanes(const F8& x, const F8& y, const F8& z) {
        const F8 squared = x * x + y * y + z * z;
        F8 out;
        for (int l = 0; l < kLanes; ++l) out[l] = std::sqrt(squared[l]);
        return out;
    }

    // A point operator on each lane's point (a translation, the common one, in vectors).
    static void pointLanes(Op op, const float* k, const F8& x, const F8& y, const F8& z, F8& ox,
                           F8& oy, F8& oz) {
        if (op == Op::Translate) {
            ox = x - k[0];
            oy = y - k[1];
            oz = z - k[2];
            return;
        }
        for (int l = 0; l < kLanes; ++l) {
            const Vec3 q = tape_ops::pointOp(op, Vec3(x[l], y[l], z[l]), k);
            ox[l] = q.x;
            oy[l] = q.y;
            oz[l] = q.z;
        }
    }

    // A primitive's value at each lane's point.
    static F8 primitiveLanes(Op op, const F8& x, const F8& y, const F8& z, const float* k) {
        F8 v = splat(kInfinity);
        switch (op) {
#define SDFT_PRUNE_PRIMITIVE(Kind, name, eval, ...)                              \
    case Op::Kind:                                                               \
        for (int l = 0; l < kLanes; ++l) v[l] = eval(Vec3(x[l], y[l], z[l]), k); \
        break;
            SDFT_PRIMITIVES(SDFT_PRUNE_PRIMITIVE)
#undef SDFT_PRUNE_PRIMITIVE
            default:
                break;
        }
        return v;
    }

    // The interval of a scalar instruction's result from its operands', per lane (combine: the
    // folds; the unary ops; unknown for grids and displacements).
    static void scalarLanes(Op op, const LaneInterval& a, const LaneInterval& b, const float* k,
                            LaneInterval& r) {
        // The smooth ops lie within k/4 of the hard ones (operators.h); a hard op's k may point
        // past the tape's last constant, so it is read only for the smooth ones.
        const bool smooth = op >= Op::SmoothUnion && op <= Op::SmoothDifference;
        const float blend = smooth && k[0] > 0 ? 0.25f * k[0] : 0.0f;
        const F8 inf = splat(kInfinity);
        switch (op) {
            case Op::Union:
            case Op::SmoothUnion:
                r = {vmin(a.lo, b.lo) - blend, vmin(a.hi, b.hi)};
                return;
            case Op::Intersection:
            case Op::SmoothIntersection:
                r = {vmax(a.lo, b.lo), vmax(a.hi, b.hi) + blend};
                return;
            case Op::Difference:
            case Op::SmoothDifference:
                r = {vmax(a.lo, -b.hi), vmax(a.hi, -b.lo) + blend};
                return;
            case Op::Morph:
                if (k[0] >= 0 && k[0] <= 1) {
                    r = {(1 - k[0]) * a.lo + k[0] * b.lo, (1 - k[0]) * a.hi + k[0] * b.hi};
                    return;
                }
                break;
            case Op::Complement:
                r = {-a.hi, -a.lo};
                return;
            case Op::Copy:
                r = a;
                return;
            case Op::ScaleValue:
                r = k[0] > 0   ? LaneInterval{a.lo * k[0], a.hi * k[0]}
                    : k[0] < 0 ? LaneInterval{a.hi * k[0], a.lo * k[0]}
                               : LaneInterval{F8{}, F8{}};
                return;
            case Op::RepeatBound:  // min(a, a bound)
                r = {-inf, a.hi};
                return;
            case Op::FloorByBounds:  // max(a, a box distance)
                r = {a.lo, inf};
                return;
            default:  // a grid, a displacement
                break;
        }
        r = {-inf, inf};
    }

    // An operand's values over the cell as its hard fold sees them (a difference negates all but
    // the first): the side that bounds the fold's result, and the side that rules the operand
    // out. Vectors, not an interval's copy (copied member by member, it stalled the loads).
    F8 boundOf(Op op, int32_t m) const {
        const LaneInterval& b = m_s.out[m_s.rhsDef[m]];
        return op == Op::Union ? b.hi : op == Op::Intersection ? b.lo : -b.hi;
    }
    F8 nearOf(Op op, int32_t m) const {
        const LaneInterval& b = m_s.out[m_s.rhsDef[m]];
        return op == Op::Union ? b.lo : op == Op::Intersection ? b.hi : -b.lo;
    }
    // The lanes in which the values whose near side is `near` all lie beyond the chain's best
    // bound.
    static LaneMask ruledOut(const PruneScratch::Chain& c, const F8& near) {
        return maskOf(c.op == Op::Union ? near > c.best : near < c.best);
    }

    // Hard folds, as chains of one operator through the accumulator (min, max and max(a, -b)
    // are associative, so nested folds of the same operator form one chain): member i joins the
    // chain of its accumulator's or starts one, and tightens the chain's best bound.
    void joinChain(int32_t i) {
        std::vector<PruneScratch::Chain>& chains = m_s.chains;
        const Op op = m_t.instrs[i].op;
        const int32_t j = m_s.accDef[i];
        if (j >= 0 && m_t.instrs[j].op == op && m_s.chainOf[j] >= 0) {
            m_s.chainOf[i] = m_s.chainOf[j];
        } else {
            m_s.chainOf[i] = static_cast<int32_t>(chains.size());
            const F8 unknown = splat(op == Op::Union ? kInfinity : -kInfinity);
            const F8 best = j < 0 ? unknown : (op == Op::Union ? m_s.out[j].hi : m_s.out[j].lo);
            chains.push_back({op, j, i, j >= 0, 0, best});
        }
        m_s.hard.push_back(i);
        PruneScratch::Chain& c = chains[m_s.chainOf[i]];
        if (m_s.rhsDef[i] < 0) {
            c.valid = false;
            return;
        }
        const F8 bound = boundOf(op, i);
        c.best = op == Op::Union ? vmin(c.best, bound) : vmax(c.best, bound);
    }

    // An operand whose values over the cell all lie beyond the best bound another operand of its
    // chain guarantees never decides the result. The first operand, when ruled out, gives its
    // place to the first member left (a copy of its operand); a difference's first operand is
    // never negated, so it stays.
    void decideHard() {
        std::vector<PruneScratch::Chain>& chains = m_s.chains;
        for (PruneScratch::Chain& c : chains)
            c.replaceFirst =
                c.valid && c.op != Op::Difference
                    ? ruledOut(c, c.op == Op::Union ? m_s.out[c.first].lo : m_s.out[c.first].hi)
                    : 0;
        for (const int32_t i : m_s.hard) {  // drop the ruled-out operands
            const PruneScratch::Chain& c = chains[m_s.chainOf[i]];
            if (!c.valid) continue;
            const LaneMask out = ruledOut(c, nearOf(c.op, i));
            if (out) dropOperand(i, out);
        }
        for (const int32_t i : m_s.hard) {  // the first member left replaces a dropped first
            PruneScratch::Chain& c = chains[m_s.chainOf[i]];
            const LaneMask lanes = c.replaceFirst & static_cast<LaneMask>(~m_r.drop[i]);
            if (!lanes) continue;
            dropRange(m_t.folds[c.front].fold, static_cast<uint32_t>(c.first), lanes);
            if (m_t.instrs[i].cull >= 0) m_r.drop[m_t.folds[i].operand - 1] |= lanes;
            m_r.copy[i] |= lanes;
            m_r.copied |= lanes;
            c.replaceFirst &= static_cast<LaneMask>(~lanes);
        }
    }

    // A smooth fold's operand i: zero blend weight over the whole cell (|a - b| >= k, the right
    // sign) leaves the accumulator as it was.
    void decideSmooth(int32_t i) {
        const Instr& in = m_t.instrs[i];
        const float k = m_k[in.k];
        if (!(k > 0) || m_s.accDef[i] < 0 || m_s.rhsDef[i] < 0) return;
        const float margin = k * (1 + 1e-5f);
        const LaneInterval &a = m_s.out[m_s.accDef[i]], &b = m_s.out[m_s.rhsDef[i]];
        const LaneMask inactive = maskOf(in.op == Op::SmoothUnion          ? b.lo - a.hi >= margin
                                         : in.op == Op::SmoothIntersection ? a.lo - b.hi >= margin
                                                                           : a.lo + b.lo >= margin);
        if (inactive) dropOperand(i, inactive);
    }

    // A fold member and its operand, with the operand's guard, in the given lanes.
    void dropOperand(int32_t m, LaneMask lanes) {
        const uint32_t from = m_t.folds[m].operand - (m_t.instrs[m].cull >= 0 ? 1 : 0);
        dropRange(from, static_cast<uint32_t>(m), lanes);
    }
    void dropRange(uint32_t from, uint32_t to, LaneMask lanes) {
        LaneMask* d = m_r.drop.data();
        for (uint32_t x = from; x <= to; ++x) d[x] |= lanes;
        m_r.changed |= lanes;
    }

    const FlatTape& m_t;
    const float* m_k;
    const Bounds3* m_local;
    size_t m_n;
    PruneScratch& m_s;
    PruneResult& m_r;
    Vec3 m_centre[kLanes];
    F8 m_radius;
    F8 m_half[3];  // the cells' half extents along x, y and z
    LaneMask m_lanes = 0;
};

}  // namespace sdft::prune
