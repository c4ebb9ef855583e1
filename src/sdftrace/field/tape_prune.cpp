// Hierarchical Lipschitz pruning (tape_prune.h; Barbier et al., Eurographics 2025): interval bounds
// of every instruction over a cell from the value at its centre and the Lipschitz bound of the
// primitives (every primitive is 1-Lipschitz; a point transform scales that by its stretch),
// propagated through the CSG operators; folds drop the operands those bounds rule out.
#include "sdftrace/field/tape_prune.h"

#include <sys/mman.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <mutex>
#include <new>
#include <numeric>
#include <span>
#include <utility>
#include <vector>

#include "sdftrace/exec/simd.h"
#include "sdftrace/field/tape_view.h"

namespace sdft {

namespace {

std::atomic<LeafCompaction> g_leafCompaction{LeafCompaction::Lanes};

struct Interval {
    float lo = -kInfinity, hi = kInfinity;
};

// A tape's instructions with the compiler's fold records (Tape::foldOperands), the form pruning
// reads and writes.
struct FlatTape {
    static constexpr uint32_t kMade = ~0u;  // origin: an instruction the pruning made (a copy)
    std::vector<Instr> instrs;
    std::vector<FoldOperands> folds;
    std::vector<uint32_t> origin;  // per instruction, its index in the whole tape, or kMade
    bool made = false;             // whether any origin is kMade
};

// The cells' box is the scene's (or its bounded operands') grown by this share of its diagonal;
// points outside it take the outside tape (PrunedTapes::outsideTape), which gives the same values
// at a higher cost per evaluation (a hierarchy over every operand), so the margin keeps the air
// just around the scene in cells.
constexpr float kOutsideMargin = 0.02f;

bool isCombine(Op op) { return op >= Op::Union && op <= Op::SmoothDifference; }
bool isHardCombine(Op op) { return op >= Op::Union && op <= Op::Difference; }
bool writesScalar(Op op) { return op != Op::CullIfFar && op < Op::Translate; }

// How far a point operator can move two points apart, per unit (infinite: not Lipschitz).
float stretch(Op op, const float* k) {
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

// One pass over a parent's tape prunes it for up to this many cells at once (an octree node's
// children): each instruction is decoded once and bounded over every cell, lane by lane.
constexpr int kLanes = 8;
using LaneMask = uint8_t;  // bit l: lane l

// A primitive's bounds in its frame where its value outside them is at least the distance to them
// (primitive_table.h's "dominates bounds"), else an empty box.
Bounds3 dominatedBounds(Op op, const float* k) {
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

// Eight floats (or comparison results) that the compiler keeps in vector registers, two SSE
// registers or one AVX register wide, aligned to their size in both builds (the baseline's
// default is 16 bytes, which the AVX2 build's aligned moves would fault on). min and max as
// std::min and std::max have them (the first operand where the comparison fails, NaN included),
// so the lanes compute what the scalar code would. Every function that handles them is inlined
// into the pass's two builds (SDFT_TARGET_AVX2 and SDFT_TARGET_BASELINE flatten), so -Wpsabi's
// warning that their calling convention differs without AVX does not apply; parameters are
// passed by reference all the same.
#pragma GCC diagnostic ignored "-Wpsabi"
using F8 = float __attribute__((vector_size(kLanes * sizeof(float)), aligned(32)));
using I8 = int32_t __attribute__((vector_size(kLanes * sizeof(int32_t)), aligned(32)));
inline F8 splat(float x) { return F8{} + x; }
inline F8 vmin(const F8& a, const F8& b) { return b < a ? b : a; }
inline F8 vmax(const F8& a, const F8& b) { return a < b ? b : a; }
inline F8 vabs(const F8& a) { return a < 0 ? -a : a; }
// A comparison's lanes as bits: the sign bits of its two halves (SSE's movmskps, in both
// builds), or lane by lane.
inline LaneMask maskOf(const I8& m) {
#if SDFT_HAVE_AVX2_DISPATCH
    using F4 = float __attribute__((vector_size(4 * sizeof(float))));
    F4 lo, hi;
    std::memcpy(&lo, &m, sizeof lo);
    std::memcpy(&hi, reinterpret_cast<const char*>(&m) + sizeof lo, sizeof hi);
    return static_cast<LaneMask>(__builtin_ia32_movmskps(lo) | __builtin_ia32_movmskps(hi) << 4);
#else
    LaneMask bits = 0;
    for (int l = 0; l < kLanes; ++l) bits |= static_cast<LaneMask>((m[l] & 1) << l);
    return bits;
#endif
}

// An interval per lane.
struct LaneInterval {
    F8 lo, hi;
};

// A fold member turned into a copy of its operand (the first operand left when the first was
// dropped; Pruner::decideHard).
Instr copyOf(Instr in) {
    in.op = Op::Copy;
    in.a = in.b;
    in.b = 0;
    in.cull = -1;
    return in;
}

// A kept guard's jump in lane l's pruned tape: past its (kept) operator. `next` is
// Pruner::emit's renumbering.
uint32_t laneJump(const uint32_t* next, uint32_t jump, int lane) {
    return next[(jump - 1) * kLanes + lane] + 1;
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

// What a pass decides for its cells: per instruction, the lanes that drop it and those that turn
// it into a copy of its second operand; per lane, the tape's values over the cell.
struct PruneResult {
    std::vector<LaneMask> drop, copy;
    Interval value[kLanes];
    LaneMask changed = 0;  // the lanes that drop anything
    LaneMask copied = 0;   // the lanes that turn anything into a copy
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

// compactTape's working memory, one per thread.
struct CompactScratch {
    struct Entry {
        uint32_t first, count;  // instructions of the pruned tape: a Run when count > 1
    };
    std::vector<uint8_t> copied, starts;
    std::vector<uint32_t> entryOf;
    std::vector<Entry> entries;
};

// A pruned tape as compactTape reads it: a FlatTape's instructions as they are.
struct FlatView {
    const FlatTape& t;
    size_t size() const { return t.instrs.size(); }
    uint32_t origin(size_t j) const { return t.origin[j]; }
    Op op(size_t j) const { return t.instrs[j].op; }
    uint32_t jump(size_t j) const { return t.instrs[j].jump; }
    Instr instr(size_t j) const { return t.instrs[j]; }
};

// A pruned tape as the cells keep it, appended to `out`: each stretch of instructions that the
// whole tape has as they are (consecutive there, every jump inside) becomes one Op::Run of the
// whole tape's instructions, and the rest is copied, its jumps renumbered. `whole` is the whole
// tape's.
void compactTape(const FlatView& t, const Instr* whole, std::vector<Instr>& out,
                 CompactScratch& scratch) {
    const size_t n = t.size();
    auto verbatim = [&](size_t j) { return t.origin(j) != FlatTape::kMade; };
    auto follows = [&](size_t j) {  // j continues j - 1's stretch of the whole tape
        return j > 0 && verbatim(j) && verbatim(j - 1) && t.origin(j) == t.origin(j - 1) + 1;
    };
    // A guard may sit in a Run when its operand is the whole tape's, unbroken; the others are
    // copied, and the instruction each jumps to must start an entry.
    std::vector<uint8_t>&copied = scratch.copied, &starts = scratch.starts;
    copied.assign(n, 0);
    starts.assign(n + 1, 0);
    for (size_t j = 0; j < n; ++j) {
        if (!verbatim(j)) {
            copied[j] = 1;
            continue;
        }
        if (t.op(j) != Op::CullIfFar) continue;
        const uint32_t jump = t.jump(j);
        bool intact = jump - j == whole[t.origin(j)].jump - t.origin(j);
        for (size_t i = j + 1; intact && i < jump; ++i) intact = follows(i);
        if (!intact) copied[j] = 1, starts[jump] = 1;
    }
    // The entries: a Run per stretch of two or more, the rest one by one.
    std::vector<uint32_t>& entryOf = scratch.entryOf;
    entryOf.assign(n + 1, 0);
    std::vector<CompactScratch::Entry>& entries = scratch.entries;
    entries.clear();
    for (size_t j = 0; j < n;) {
        size_t e = j + 1;
        if (!copied[j])
            while (e < n && !copied[e] && !starts[e] && follows(e)) ++e;
        entryOf[j] = static_cast<uint32_t>(entries.size());
        entries.push_back({static_cast<uint32_t>(j), static_cast<uint32_t>(e - j)});
        j = e;
    }
    entryOf[n] = static_cast<uint32_t>(entries.size());
    for (const CompactScratch::Entry& e : entries) {
        Instr in{};
        if (e.count > 1) {
            in.op = Op::Run;
            in.k = t.origin(e.first);
            in.jump = t.origin(e.first) + e.count;
        } else {
            in = t.instr(e.first);
            if (in.op == Op::CullIfFar) in.jump = entryOf[in.jump];
        }
        out.push_back(in);
    }
}

// The tapes of a pass's leaf lanes as compactTape would make them from their pruned tapes, made
// in one walk over the parent's tape for all of them, each lane's entries as its kept
// instructions come (no pruned tape of their own). `next` is Pruner::emit's, with the lanes
// counted. An instruction that extends every lane's open stretch (the common case) is one vector
// step; where a lane's entry ends, that lane goes one by one.
class LaneCompactor {
  public:
    struct Lane {
        std::vector<Instr> out;  // the compacted tape
        // Copied guards whose jump is still to be set, innermost last: their entry, and the
        // parent's instruction they jump to (the lane's first kept one from there starts an
        // entry, as compactTape's `starts`).
        std::vector<std::pair<uint32_t, uint32_t>> pending;
        Instr first{};  // the open stretch's first instruction
    };
    struct Job {
        const FlatTape& t;
        const PruneResult& r;
        LaneMask lanes;
        const uint32_t* next;
        const Instr* whole;
        std::array<Lane, kLanes>& out;
    };

    static void run(const Job& job) {
        if (useAvx2())
            runAvx2(job);
        else
            runBaseline(job);
    }

  private:
    // Per lane, in vector registers: the open stretch (verbatim instructions, consecutive in the
    // whole tape; `open` says which lanes have one): its last origin and length; and the
    // innermost pending guard's target (kNone: none).
    struct State {
        I8 last{}, count{}, target{};
        LaneMask open = 0;
    };
    static constexpr int32_t kNone = INT32_MAX;

    SDFT_TARGET_AVX2 static void runAvx2(const Job& job) { pass(job); }
    SDFT_TARGET_BASELINE static void runBaseline(const Job& job) { pass(job); }

    static void pass(const Job& job) {
        const FlatTape& t = job.t;
        const PruneResult& r = job.r;
        for (int l = 0; l < kLanes; ++l) {
            job.out[l].out.clear();
            job.out[l].pending.clear();
        }
        State st;
        st.target = I8{} + kNone;
        const I8 laneBit = {1, 2, 4, 8, 16, 32, 64, 128};
        const LaneMask mayCopy = t.made ? job.lanes : (r.copied & job.lanes);
        const size_t n = t.instrs.size();
        for (size_t i = 0; i < n; ++i) {
            const unsigned keep = ~r.drop[i] & job.lanes;
            if (!keep) continue;
            const Instr& in = t.instrs[i];
            const uint32_t origin = t.origin[i];
            // compactTape's `copied`: not the whole tape's, or a guard over an operand that is
            // not the whole tape's unbroken (as long, and no copies in it: as the pruning is, a
            // member that becomes a copy loses its guard, so only the length decides; the copies
            // are looked for all the same where there may be some).
            unsigned copied = origin == FlatTape::kMade ? keep : r.copy[i] & keep;
            if (in.op == Op::CullIfFar && origin != FlatTape::kMade) {
                I8 g, j;
                std::memcpy(&g, job.next + i * kLanes, sizeof g);
                std::memcpy(&j, job.next + (in.jump - 1) * kLanes, sizeof j);
                const auto span = static_cast<int32_t>(job.whole[origin].jump - origin);
                unsigned broken = maskOf(j + 1 - g != span) & keep;
                for (unsigned m = keep & ~broken & mayCopy; m; m &= m - 1) {
                    const int l = std::countr_zero(m);
                    if (anyCopy(t, r, i + 1, in.jump, l)) broken |= 1u << l;
                }
                copied |= broken;
            }
            const I8 o = I8{} + static_cast<int32_t>(origin);
            const unsigned extend =
                keep & st.open & ~copied &
                maskOf((st.last + 1 == o) & (static_cast<int32_t>(i) < st.target));
            const I8 grow = (laneBit & static_cast<int32_t>(extend)) == laneBit;  // true is -1
            st.last = grow ? o : st.last;
            st.count -= grow;
            for (unsigned m = keep & ~extend; m; m &= m - 1) {
                const int l = std::countr_zero(m);
                start(st, job.out[l], l, static_cast<int32_t>(i), in, r.copy[i] >> l & 1, origin,
                      copied >> l & 1);
            }
        }
        for (int l = 0; l < kLanes; ++l) {
            if (!(job.lanes >> l & 1)) continue;
            close(st, job.out[l], l);
            resolve(st, job.out[l], l, kNone);  // a jump to the end: past the last entry
        }
    }

    // Lane l's instruction i of the parent, `in` (turned into a copy in the lane: laneCopy), that
    // does not extend the lane's open stretch: it starts an entry.
    static void start(State& st, Lane& c, int l, int32_t i, const Instr& in, bool laneCopy,
                      uint32_t origin, bool copied) {
        close(st, c, l);
        resolve(st, c, l, i);
        if (copied) {  // an entry of its own
            c.out.push_back(laneCopy ? copyOf(in) : in);
            if (in.op == Op::CullIfFar) pend(st, c, l, in.jump);
            return;
        }
        st.open |= static_cast<LaneMask>(1u << l);
        c.first = in;  // verbatim: not a copy
        st.count[l] = 1;
        st.last[l] = static_cast<int32_t>(origin);
    }
    // Lane l's open stretch as its entry: a Run, or its one instruction.
    static void close(State& st, Lane& c, int l) {
        if (!(st.open >> l & 1)) return;
        st.open &= static_cast<LaneMask>(~(1u << l));
        const auto count = static_cast<uint32_t>(st.count[l]),
                   end = static_cast<uint32_t>(st.last[l]) + 1;
        if (count > 1) {
            Instr run{};
            run.op = Op::Run;
            run.k = end - count;
            run.jump = end;
            c.out.push_back(run);
            return;
        }
        c.out.push_back(c.first);
        if (c.first.op == Op::CullIfFar) pend(st, c, l, c.first.jump);
    }
    // The last entry of lane l, a guard, jumps to the entry that starts at parent instruction
    // `target` or after it.
    static void pend(State& st, Lane& c, int l, uint32_t target) {
        c.pending.emplace_back(static_cast<uint32_t>(c.out.size() - 1), target);
        st.target[l] = static_cast<int32_t>(target);
    }
    // The guards that jump to parent instruction `i` or before it jump to the next entry.
    static void resolve(State& st, Lane& c, int l, int32_t i) {
        while (!c.pending.empty() && static_cast<int32_t>(c.pending.back().second) <= i) {
            c.out[c.pending.back().first].jump = static_cast<uint32_t>(c.out.size());
            c.pending.pop_back();
        }
        st.target[l] = c.pending.empty() ? kNone : static_cast<int32_t>(c.pending.back().second);
    }
    // Whether lane l keeps a copy among the parent's instructions [from, to).
    static bool anyCopy(const FlatTape& t, const PruneResult& r, size_t from, size_t to, int l) {
        for (size_t i = from; i < to; ++i)
            if (!(r.drop[i] >> l & 1) && ((r.copy[i] >> l & 1) || t.origin[i] == FlatTape::kMade))
                return true;
        return false;
    }
};

// Room for `n` elements, backed by huge pages where the system gives them on request: a build
// writes tens of megabytes of fresh leaf tapes, and faulting them in 4 KiB pages cost more than
// computing them (about 10 us a page on a virtual machine).
template <typename T>
void reserveLarge(std::vector<T>& v, size_t n) {
    try {
        v.reserve(n);
    } catch (const std::bad_alloc&) {  // a system that counts address space: grow as needed
        return;
    }
#ifdef MADV_HUGEPAGE
    constexpr uintptr_t kHuge = uintptr_t{1} << 21;
    const auto begin = (reinterpret_cast<uintptr_t>(v.data()) + kHuge - 1) & ~(kHuge - 1);
    const auto end = reinterpret_cast<uintptr_t>(v.data() + v.capacity()) & ~(kHuge - 1);
    if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#endif
}

// A leaf tape stops at this many instructions: its cells share it.
constexpr size_t kSmallTape = 12;
// Tapes shorter than this are not pruned, nor those whose cells keep on average more than this
// share of the instructions.
constexpr size_t kWorthPruning = 48;
constexpr double kWorthwhileShare = 0.5;
// Under bounds culling, at least this many outer guards per instruction of a leaf tape.
constexpr double kGuardsPerLeafInstr = 0.3;
// The octree's top levels run their children in parallel; below, each subtree is one thread's.
constexpr int kParallelLevels = 2;
constexpr int kMaxLevels = 32;
// The leaf tapes' array is reserved for this many entries per cell (compactTape: a few Runs and
// copies, a hundred at most in the benchmark's scenes), at most kMaxReserve: address space, not
// memory, and growing it would copy and fault in the whole array again.
constexpr size_t kLeafGuess = 256, kMaxReserve = size_t{1} << 25;

class Builder {
  public:
    // Leaf cells of edge about `edge` over `box`: a power of two along each axis.
    Builder(const Tape& tape, const Bounds3& box, float edge) : m_consts(tape.constants().data()) {
        m_out = std::make_shared<PrunedTapes>();
        m_out->box = box;
        const Vec3 extent = box.extent();
        int range[3];
        for (int a = 0; a < 3; ++a) {
            int r = 1;
            while (r * edge < extent[a] && r < 64) r *= 2;
            m_out->res[a] = range[a] = r;
        }
        const size_t cells = static_cast<size_t>(range[0]) * range[1] * range[2];
        m_out->cellTape.assign(cells, 0);
        // Room for each thread's leaf tapes; reserved, not touched.
        const size_t whole = tape.size();
        m_leafGuess = std::min(cells * std::min(whole, kLeafGuess), kMaxReserve);
        m_outsideGuess = 2 * whole + 64;
        FlatTape root;
        root.instrs.assign(tape.instructions().begin(), tape.instructions().end());
        root.folds.assign(tape.foldOperands().begin(), tape.foldOperands().end());
        root.origin.resize(root.instrs.size());
        std::iota(root.origin.begin(), root.origin.end(), 0u);
        m_whole = tape.instructions().data();
        m_local.reserve(tape.size());
        for (const Instr& in : tape.instructions())
            m_local.push_back(in.op < Op::Grid ? dominatedBounds(in.op, m_consts + in.k)
                                               : Bounds3{});
        // The root cell pruned from the whole tape, then its subtree.
        Local& local = m_locals.local();
        PruneResult result;
        Pruner(root, m_consts, m_local.data(), &box, 1, local.scratch, result).run();
        FlatTape pruned;
        FlatTape* out = &pruned;
        uint32_t kept[kLanes];
        Pruner::countKept(result, kept);
        if (result.changed) Pruner::emit({root, result, kept, 1, &out, 0, local.scratch.next});
        int32_t memo = -1;
        Cell cell{box, result.value[0], {0, 0, 0}, {range[0], range[1], range[2]}};
        node(result.changed ? pruned : root, memo, cell, 0);
        gather();
    }
    std::shared_ptr<PrunedTapes> finish() { return m_out; }
    // The mean instructions per leaf cell, against the whole tape's.
    double meanLeafInstrs() const {
        double sum = 0;
        for (uint32_t t : m_out->cellTape) sum += m_lengths[t];
        return sum / static_cast<double>(m_out->cellTape.size());
    }

  private:
    // One thread's: its pruner's scratch, and per level of the subtree it descends, the pass
    // over that level's tape and the tape of the child it is in.
    struct Local {
        PruneScratch scratch;
        std::vector<PruneResult> results = std::vector<PruneResult>(kMaxLevels);
        std::vector<std::array<FlatTape, kLanes>> levels =
            std::vector<std::array<FlatTape, kLanes>>(kMaxLevels);
        std::array<LaneCompactor::Lane, kLanes> lanes;  // a pass's leaf lanes
        CompactScratch compactScratch;
        // The leaf tapes this thread made (compactTape's form), one after another, and per
        // tape its id, first instruction, instructions and instructions before compactTape.
        std::vector<Instr> leafInstrs;
        std::vector<uint32_t> leafId, leafFirst, leafCount, leafLength;
    };
    // An octree node: its box, the field's values over it, and its leaf cells first[a] +
    // [0, range[a]).
    struct Cell {
        Bounds3 box;
        Interval value;
        int first[3], range[3];
    };

    // Whether a cell whose tape has `size` instructions is a leaf; if not, the axes it splits:
    // those at least half as long as its longest, so that its cells stay about cubic.
    static bool isLeaf(const Cell& cell, size_t size, bool split[3]) {
        const Vec3 extent = cell.box.extent();
        const float longest = maxComponent(extent);
        for (int a = 0; a < 3; ++a) split[a] = cell.range[a] > 1 && extent[a] >= 0.5f * longest;
        // A cell farther than its diagonal from the surface (outside or inside) is not split:
        // rays cross it in a step or two, so a shorter tape would hardly be used.
        const float diagonal = length(extent);
        const bool far = cell.value.lo > diagonal || cell.value.hi < -diagonal;
        return !(split[0] || split[1] || split[2]) || far || size <= kSmallTape;
    }

    // The subtree of `cell`, whose tape is `tape` (its leaf id, once it has one, is `memo`): a
    // leaf, or eight (four, two) children pruned from `tape` in one pass. Children that are
    // leaves are compacted straight from the pass (no tape of their own); the others get their
    // tapes and subtrees.
    void node(const FlatTape& tape, int32_t& memo, const Cell& cell, int level) {
        SDFT_CHECK(level < kMaxLevels);
        bool split[3];
        if (isLeaf(cell, tape.instrs.size(), split)) {
            Local& local = m_locals.local();
            leaf(leafId(local, memo, static_cast<uint32_t>(tape.instrs.size()),
                        [&](std::vector<Instr>& mine) {
                            compactTape(FlatView{tape}, m_whole, mine, local.compactScratch);
                        }),
                 cell);
            return;
        }
        Cell children[kLanes];
        Bounds3 boxes[kLanes];
        int n = 0;
        for (int c = 0; c < 8; ++c)  // child c: bit a says which half along a split axis
            if (childCell(cell, split, c, children[n])) boxes[n] = children[n].box, ++n;
        // The top levels' passes and tapes are the node's own (their children run in parallel,
        // and a waiting thread may take up another node of the same level); below, its thread's.
        Local& local = m_locals.local();
        PruneResult ownResult;
        std::array<FlatTape, kLanes> ownTapes;
        const bool parallel = level < kParallelLevels;
        PruneResult& result = parallel ? ownResult : local.results[level];
        std::array<FlatTape, kLanes>& tapes = parallel ? ownTapes : local.levels[level + 1];
        Pruner(tape, m_consts, m_local.data(), boxes, n, local.scratch, result).run();
        uint32_t kept[kLanes];
        Pruner::countKept(result, kept);
        LaneMask full = 0, leaves = 0;
        for (int c = 0; c < n; ++c) {
            children[c].value = result.value[c];
            bool s[3];
            if (result.changed >> c & 1)
                (isLeaf(children[c], kept[c], s) ? leaves : full) |= static_cast<LaneMask>(1 << c);
        }
        if (g_leafCompaction.load(std::memory_order_relaxed) == LeafCompaction::OneByOne)
            full |= std::exchange(leaves, 0);  // each leaf its own tape, compacted as a leaf
        FlatTape* out[kLanes];
        for (int c = 0; c < kLanes; ++c) out[c] = &tapes[c];
        Pruner::emit({tape, result, kept, full, out, leaves, local.scratch.next});
        if (leaves) {  // before any subtree reuses the thread's scratch
            LaneCompactor::run(
                {tape, result, leaves, local.scratch.next.data(), m_whole, local.lanes});
            for (int c = 0; c < n; ++c) {
                if (!(leaves >> c & 1)) continue;
                const std::vector<Instr>& compact = local.lanes[c].out;
                int32_t ownMemo = -1;
                leaf(leafId(local, ownMemo, kept[c],
                            [&](std::vector<Instr>& mine) {
                                mine.insert(mine.end(), compact.begin(), compact.end());
                            }),
                     children[c]);
            }
        }
        auto child = [&](int c) {
            int32_t ownMemo = -1;
            if (full >> c & 1)
                node(tapes[c], ownMemo, children[c], level + 1);
            else if (!(leaves >> c & 1))
                node(tape, memo, children[c], level + 1);
        };
        if (parallel) {
            tbb::parallel_for(0, n, child);
        } else {
            for (int c = 0; c < n; ++c) child(c);
        }
    }

    // Child c of `cell` (bit a: the upper half along split axis a), or false where c names an
    // upper half along an axis that is not split.
    static bool childCell(const Cell& cell, const bool split[3], int c, Cell& out) {
        out = cell;
        for (int a = 0; a < 3; ++a) {
            const bool high = (c >> a) & 1;
            if (!split[a]) {
                if (high) return false;
                continue;
            }
            out.range[a] = cell.range[a] / 2;
            const float mid = 0.5f * (cell.box.lo[a] + cell.box.hi[a]);
            if (high) {
                out.first[a] += out.range[a];
                out.box.lo[a] = mid;
            } else {
                out.box.hi[a] = mid;
            }
        }
        return true;
    }

    // A leaf: its cells take the id of its tape.
    void leaf(uint32_t id, const Cell& cell) {
        const int* res = m_out->res;
        for (int z = cell.first[2]; z < cell.first[2] + cell.range[2]; ++z)
            for (int y = cell.first[1]; y < cell.first[1] + cell.range[1]; ++y)
                std::fill_n(m_out->cellTape.begin() +
                                (static_cast<size_t>(z) * res[1] + y) * res[0] + cell.first[0],
                            cell.range[0], id);
    }

    // The id of a leaf's tape: `memo`, or a new one for the tape (`length` instructions before
    // compactTape), which compact(mine) appends to the thread's leaf tapes (gather() puts them
    // together). Only the memo is shared between threads.
    template <typename Compact>
    uint32_t leafId(Local& local, int32_t& memo, uint32_t length, Compact&& compact) {
        {
            std::lock_guard<std::mutex> lock(m_mutex);
            if (memo >= 0) return static_cast<uint32_t>(memo);
        }
        std::vector<Instr>& mine = local.leafInstrs;
        if (mine.capacity() == 0) reserveLarge(mine, m_leafGuess);
        const size_t first = mine.size();
        compact(mine);
        uint32_t id;
        {
            std::lock_guard<std::mutex> lock(m_mutex);
            if (memo >= 0) {  // a sibling's, meanwhile
                mine.resize(first);
                return static_cast<uint32_t>(memo);
            }
            memo = static_cast<int32_t>(id = m_tapes++);
        }
        local.leafId.push_back(id);
        local.leafFirst.push_back(static_cast<uint32_t>(first));
        local.leafCount.push_back(static_cast<uint32_t>(mine.size() - first));
        local.leafLength.push_back(length);
        return id;
    }

    // The threads' leaf tapes into the cells' one array: the longest thread's array becomes it
    // (no copy; reserved with room to spare for the outside tape after the leaves,
    // addOutsideTape's operands and a guard and union per group), the others appended.
    void gather() {
        Local* longest = nullptr;
        for (Local& l : m_locals)
            if (!longest || l.leafInstrs.size() > longest->leafInstrs.size()) longest = &l;
        std::vector<Instr>& all = m_out->instrs;
        if (longest) all = std::move(longest->leafInstrs);
        size_t total = all.size() + m_outsideGuess;
        for (const Local& l : m_locals) total += l.leafInstrs.size();
        if (all.capacity() < total) all.reserve(total);
        m_out->spans.assign(2 * size_t{m_tapes}, 0);
        m_lengths.assign(m_tapes, 0);
        for (Local& l : m_locals) {
            const auto base = static_cast<uint32_t>(&l == longest ? 0 : all.size());
            if (&l != longest) all.insert(all.end(), l.leafInstrs.begin(), l.leafInstrs.end());
            for (size_t k = 0; k < l.leafId.size(); ++k) {
                const uint32_t id = l.leafId[k];
                m_out->spans[2 * size_t{id}] = base + l.leafFirst[k];
                m_out->spans[2 * size_t{id} + 1] = l.leafCount[k];
                m_lengths[id] = l.leafLength[k];
            }
        }
    }

    const float* m_consts;
    std::shared_ptr<PrunedTapes> m_out;
    tbb::enumerable_thread_specific<Local> m_locals;
    std::mutex m_mutex;
    const Instr* m_whole = nullptr;
    std::vector<Bounds3> m_local;  // per instruction of the whole tape: dominatedBounds
    size_t m_leafGuess = 0, m_outsideGuess = 0;  // reserveLarge's sizes
    uint32_t m_tapes = 0;                        // leaf tapes so far (under m_mutex)
    std::vector<uint32_t> m_lengths;  // per leaf tape, its instructions before compactTape
};

// The guards (CullIfFar) that every evaluation of the whole tape tests: those outside any other
// guard's operand.
size_t outerGuards(std::span<const Instr> instrs) {
    size_t count = 0;
    for (size_t j = 0; j < instrs.size();) {
        if (instrs[j].op == Op::CullIfFar) {
            ++count;
            j = instrs[j].jump;
        } else {
            ++j;
        }
    }
    return count;
}

// The box the cells cover before its margin: the scene's bounds, or (a top-level union with
// planes) those of its bounded operands.
Bounds3 cellBox(const Tape& tape, const Node& root) {
    Bounds3 box = tape.bounds();  // nodeBounds(root), which compileTape has taken
    if ((!box.finite() || box.empty()) && root.kind == NodeKind::Union) {
        box = Bounds3{};
        for (const NodePtr& c : root.children) {
            const Bounds3 b = nodeBounds(*c);
            if (b.finite()) box = unite(box, b);
        }
    }
    if (box.empty() || !box.finite()) return Bounds3{};
    return box;
}

}  // namespace

LeafCompaction setLeafCompaction(LeafCompaction way) { return g_leafCompaction.exchange(way); }

bool mayPrune(const Tape& tape) {
    // Small tapes gain nothing from cells (their lookups cost more than they save).
    if (tape.size() < kWorthPruning) return false;
    return std::any_of(tape.instructions().begin(), tape.instructions().end(),
                       [](const Instr& in) { return isCombine(in.op); });
}

std::shared_ptr<PrunedTapes> buildPrunedTapes(const Tape& tape, const Node& root) {
    if (!mayPrune(tape)) return nullptr;
    size_t primitives = 0;
    for (const Instr& in : tape.instructions()) primitives += in.op <= Op::Grid;
    Bounds3 box = cellBox(tape, root);
    if (box.empty()) return nullptr;
    // About one leaf cell per primitive along the longest axis, 2 to 64 cells.
    const double perAxis = std::cbrt(static_cast<double>(primitives));
    const int levels = std::clamp(static_cast<int>(std::lround(std::log2(perAxis))) + 1, 1, 6);
    box = box.expanded(kOutsideMargin * length(box.extent()) + 1e-6f);
    Builder builder(tape, box, maxComponent(box.extent()) / static_cast<float>(1 << levels));
    // Cells whose tapes are not much shorter than the whole are not worth their lookups, nor,
    // under bounds culling, those of a few big operands (a handful of blended strokes): culling
    // already skips the far ones after one guard each, and what pruning saves is those guards.
    const double leaf = builder.meanLeafInstrs();
    if (leaf > kWorthwhileShare * static_cast<double>(tape.size())) return nullptr;
    const size_t guards = outerGuards(tape.instructions());
    if (guards > 0 && static_cast<double>(guards) < kGuardsPerLeafInstr * leaf) return nullptr;
    return builder.finish();
}

}  // namespace sdft
