// Hierarchical Lipschitz pruning (tape_prune.h; Barbier et al., Eurographics 2025): interval bounds
// of every instruction over a cell from the value at its centre and the Lipschitz bound of the
// primitives (every primitive is 1-Lipschitz; a point transform scales that by its stretch),
// propagated through the CSG operators; folds drop the operands those bounds rule out.
#include "sdftrace/field/tape_prune.h"

#include <sys/mman.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <new>
#include <numeric>
#include <span>
#include <vector>

#include "sdftrace/field/tape_view.h"

namespace sdft {

namespace {

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
};

// The cells' box is the scene's (or its bounded operands') grown by this share of its diagonal;
// points outside it take the outside tape (PrunedTapes::outsideTape), which gives the same values
// at a higher cost per evaluation (a hierarchy over every operand), so the margin keeps the air
// just around the scene in cells.
constexpr float kOutsideMargin = 0.02f;

bool isCombine(Op op) { return op >= Op::Union && op <= Op::SmoothDifference; }
bool isHardCombine(Op op) { return op >= Op::Union && op <= Op::Difference; }
bool writesScalar(Op op) { return op != Op::CullIfFar && op < Op::Translate; }

// The interval of a binary op's result from its operands' (operators.h: the polynomial smooth
// minimum lies within k/4 below the minimum). Only the smooth ops and morph have constants (a
// hard op's k may point past the tape's last constant).
Interval combine(Op op, Interval a, Interval b, const float* k) {
    const bool smooth = op >= Op::SmoothUnion && op <= Op::SmoothDifference;
    const float blend = smooth && k[0] > 0 ? 0.25f * k[0] : 0.0f;
    switch (op) {
        case Op::Union:
            return {std::min(a.lo, b.lo), std::min(a.hi, b.hi)};
        case Op::Intersection:
            return {std::max(a.lo, b.lo), std::max(a.hi, b.hi)};
        case Op::Difference:
            return {std::max(a.lo, -b.hi), std::max(a.hi, -b.lo)};
        case Op::SmoothUnion:
            return {std::min(a.lo, b.lo) - blend, std::min(a.hi, b.hi)};
        case Op::SmoothIntersection:
            return {std::max(a.lo, b.lo), std::max(a.hi, b.hi) + blend};
        case Op::SmoothDifference:
            return {std::max(a.lo, -b.hi), std::max(a.hi, -b.lo) + blend};
        case Op::Morph:
            if (k[0] >= 0 && k[0] <= 1)
                return {(1 - k[0]) * a.lo + k[0] * b.lo, (1 - k[0]) * a.hi + k[0] * b.hi};
            return {};
        default:
            return {};
    }
}

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

// The pruner's working memory, one per thread, reused from cell to cell (a build visits tens of
// thousands of cells; allocating per cell cost more than the pruning).
struct PruneScratch {
    struct Chain {
        Op op;
        int32_t first, front;  // the fold's first operand, its first member
        float best;            // the best bound an operand guarantees
        bool valid, replaceFirst;
    };
    std::vector<Interval> out;
    std::vector<int32_t> accDef, rhsDef, chainOf;
    std::vector<uint8_t> drop, copy;
    std::vector<uint32_t> next;
    std::vector<Chain> chains;
    std::vector<int32_t> hard;  // the hard folds' members, in order
};

// A tape pruned for the points of a cell: each fold operand whose value over the cell, bounded by
// its value at the cell's centre and the Lipschitz bound of its subtree, can never be the one
// that decides the fold is removed (hard union, intersection and difference), or whose blend
// weight is zero over the cell (smooth union, intersection and difference: |a - b| >= k). The
// result equals the tape's at every point of the cell (up to one rounding of a smooth blend's
// a + (b - a) at weight 1). Operands under a grid, a repetition or a displacement are kept.
class Pruner {
  public:
    Pruner(const FlatTape& t, const float* consts, const Bounds3& cell, PruneScratch& s)
        : m_t(t), m_k(consts), m_n(t.instrs.size()), m_s(s) {
        m_centre = (cell.lo + cell.hi) * 0.5f;
        m_radius = 0.5f * length(cell.hi - cell.lo);
        // accDef, rhsDef and chainOf are read only where bounds() wrote them (folds).
        m_s.out.resize(m_n);
        m_s.accDef.resize(m_n);
        m_s.rhsDef.resize(m_n);
        m_s.chainOf.resize(m_n);
        m_s.drop.assign(m_n, 0);
        m_s.copy.assign(m_n, 0);
        m_s.chains.clear();
        m_s.hard.clear();
    }
    // The tape's values over the cell (its last result's interval), once run.
    Interval value() const { return m_value; }
    // Whether anything is dropped; emit() then writes the pruned tape.
    bool run() {
        bounds();
        decideHard();
        return m_changed;
    }

    // The kept instructions, renumbered: jumps, fold records, copies.
    void emit(FlatTape& out) const {
        const std::vector<uint8_t>& drop = m_s.drop;
        std::vector<uint32_t>& next = m_s.next;  // new index of the first kept instruction >= i
        next.resize(m_n + 1);
        out.instrs.clear();
        out.folds.clear();
        out.origin.clear();
        uint32_t kept = 0;
        for (size_t i = 0; i < m_n; ++i) {
            next[i] = kept;
            if (drop[i]) continue;
            ++kept;
            Instr in = m_t.instrs[i];
            FoldOperands f{};
            if (m_s.copy[i]) {
                in.op = Op::Copy;
                in.a = in.b;
                in.b = 0;
                in.cull = -1;
            } else if (isCombine(in.op)) {  // fold records point back: renumbered already
                f = {next[m_t.folds[i].operand], next[m_t.folds[i].fold]};
            }
            out.instrs.push_back(in);
            out.folds.push_back(f);
            out.origin.push_back(m_s.copy[i] ? FlatTape::kMade : m_t.origin[i]);
        }
        next[m_n] = kept;
        for (Instr& in : out.instrs)  // guards jump forward, past their (kept) operator
            if (in.op == Op::CullIfFar) in.jump = next[in.jump - 1] + 1;
    }

  private:
    // Forward pass: every scalar instruction's interval over the cell; smooth folds decided and
    // hard ones gathered into chains on the way.
    void bounds() {
        Vec3 pc[kTapeMaxPointRegs];
        float ps[kTapeMaxPointRegs];
        Interval sr[kTapeMaxScalarRegs];
        int32_t writer[kTapeMaxScalarRegs];
        std::fill_n(writer, kTapeMaxScalarRegs, -1);
        pc[0] = m_centre;
        ps[0] = 1;
        for (size_t i = 0; i < m_n; ++i) {
            const Instr& in = m_t.instrs[i];
            const float* k = m_k + in.k;
            Interval r;
            const Op op = in.op;
            if (op == Op::CullIfFar) continue;
            if (op < Op::Grid) {
                const float v = tape_ops::primitive(op, pc[in.a], k);
                const float reach = m_radius * ps[in.a];
                if (std::isfinite(v) && reach < kInfinity) {
                    // A margin for the rounding of the centre's value and the radius.
                    const float pad = 1e-5f * (std::fabs(v) + reach) + 1e-7f;
                    r = {v - reach - pad, v + reach + pad};
                }
            } else if (op == Op::Grid) {
                r = {};
            } else if (op <= Op::Morph) {
                m_s.accDef[i] = writer[in.a];
                m_s.rhsDef[i] = writer[in.b];
                r = combine(op, sr[in.a], sr[in.b], k);
                if (isHardCombine(op))
                    joinChain(static_cast<int32_t>(i));
                else if (op != Op::Morph)
                    decideSmooth(static_cast<int32_t>(i));
            } else if (op == Op::Complement) {
                r = {-sr[in.a].hi, -sr[in.a].lo};
            } else if (op == Op::Copy) {
                r = sr[in.a];
            } else if (op == Op::ScaleValue) {
                const Interval a = sr[in.a];
                r = k[0] > 0 ? Interval{a.lo * k[0], a.hi * k[0]}
                             : (k[0] < 0 ? Interval{a.hi * k[0], a.lo * k[0]} : Interval{0, 0});
            } else if (op == Op::RepeatBound) {
                r = {-kInfinity, sr[in.a].hi};  // min(a, a bound)
            } else if (op == Op::FloorByBounds) {
                r = {sr[in.a].lo, kInfinity};  // max(a, a box distance)
            } else if (op == Op::Displace) {
                r = {};
            } else {  // a point operator
                pc[in.out] = tape_ops::pointOp(op, pc[in.a], k);
                ps[in.out] = ps[in.a] * stretch(op, k);
                if (!isFinite(pc[in.out])) ps[in.out] = kInfinity;
                continue;
            }
            if (!(r.lo == r.lo)) r.lo = -kInfinity;
            if (!(r.hi == r.hi)) r.hi = kInfinity;
            m_s.out[i] = r;
            if (writesScalar(op)) {
                sr[in.out] = r;
                writer[in.out] = static_cast<int32_t>(i);
                m_value = r;
            }
        }
    }

    // An operand's interval as its hard fold sees it (a difference negates all but the first).
    Interval operand(Op op, int32_t m) const {
        const Interval b = m_s.out[m_s.rhsDef[m]];
        return op == Op::Difference ? Interval{-b.hi, -b.lo} : b;
    }
    static bool ruledOut(const PruneScratch::Chain& c, Interval v) {
        return c.op == Op::Union ? v.lo > c.best : v.hi < c.best;
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
            const Interval a = j >= 0 ? m_s.out[j] : Interval{};
            chains.push_back({op, j, i, op == Op::Union ? a.hi : a.lo, j >= 0, false});
        }
        m_s.hard.push_back(i);
        PruneScratch::Chain& c = chains[m_s.chainOf[i]];
        if (m_s.rhsDef[i] < 0) {
            c.valid = false;
            return;
        }
        const Interval v = operand(op, i);
        c.best = op == Op::Union ? std::min(c.best, v.hi) : std::max(c.best, v.lo);
    }

    // An operand whose values over the cell all lie beyond the best bound another operand of its
    // chain guarantees never decides the result. The first operand, when ruled out, gives its
    // place to the first member left (a copy of its operand); a difference's first operand is
    // never negated, so it stays.
    void decideHard() {
        std::vector<PruneScratch::Chain>& chains = m_s.chains;
        for (PruneScratch::Chain& c : chains)
            c.replaceFirst = c.valid && c.op != Op::Difference && ruledOut(c, m_s.out[c.first]);
        for (const int32_t i : m_s.hard) {  // drop the ruled-out operands
            const PruneScratch::Chain& c = chains[m_s.chainOf[i]];
            if (c.valid && ruledOut(c, operand(c.op, i))) dropOperand(i);
        }
        for (const int32_t i : m_s.hard) {  // the first member left replaces a dropped first
            PruneScratch::Chain& c = chains[m_s.chainOf[i]];
            if (!c.replaceFirst || m_s.drop[i]) continue;
            dropRange(m_t.folds[c.front].fold, static_cast<uint32_t>(c.first));
            if (m_t.instrs[i].cull >= 0) m_s.drop[m_t.folds[i].operand - 1] = 1;
            m_s.copy[i] = 1;
            c.replaceFirst = false;
        }
    }

    // A smooth fold's operand i: zero blend weight over the whole cell (|a - b| >= k, the right
    // sign) leaves the accumulator as it was.
    void decideSmooth(int32_t i) {
        const Instr& in = m_t.instrs[i];
        const float k = m_k[in.k];
        if (!(k > 0) || m_s.accDef[i] < 0 || m_s.rhsDef[i] < 0) return;
        const float margin = k * (1 + 1e-5f);
        const Interval a = m_s.out[m_s.accDef[i]], b = m_s.out[m_s.rhsDef[i]];
        const bool inactive = in.op == Op::SmoothUnion          ? b.lo - a.hi >= margin
                              : in.op == Op::SmoothIntersection ? a.lo - b.hi >= margin
                                                                : a.lo + b.lo >= margin;
        if (inactive) dropOperand(i);
    }

    // A fold member and its operand, with the operand's guard.
    void dropOperand(int32_t m) {
        const uint32_t from = m_t.folds[m].operand - (m_t.instrs[m].cull >= 0 ? 1 : 0);
        dropRange(from, static_cast<uint32_t>(m));
    }
    void dropRange(uint32_t from, uint32_t to) {
        std::fill(m_s.drop.begin() + from, m_s.drop.begin() + to + 1, 1);
        m_changed = true;
    }

    const FlatTape& m_t;
    const float* m_k;
    size_t m_n;
    PruneScratch& m_s;
    Vec3 m_centre;
    float m_radius = 0;
    Interval m_value;
    bool m_changed = false;
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

// A pruned tape as the cells keep it: each stretch of instructions that the whole tape has as
// they are (consecutive there, every jump inside) becomes one Op::Run of the whole tape's
// instructions, and the rest is copied, its jumps renumbered. `whole` is the whole tape's.
void compactTape(const FlatTape& t, const Instr* whole, std::vector<Instr>& out,
                 CompactScratch& scratch) {
    const size_t n = t.instrs.size();
    auto verbatim = [&](size_t j) { return t.origin[j] != FlatTape::kMade; };
    auto follows = [&](size_t j) {  // j continues j - 1's stretch of the whole tape
        return j > 0 && verbatim(j) && verbatim(j - 1) && t.origin[j] == t.origin[j - 1] + 1;
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
        const Instr& in = t.instrs[j];
        if (in.op != Op::CullIfFar) continue;
        bool intact = in.jump - j == whole[t.origin[j]].jump - t.origin[j];
        for (size_t i = j + 1; intact && i < in.jump; ++i) intact = follows(i);
        if (!intact) copied[j] = 1, starts[in.jump] = 1;
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
    out.clear();
    for (const CompactScratch::Entry& e : entries) {
        Instr in = t.instrs[e.first];
        if (e.count > 1) {
            in = Instr{};
            in.op = Op::Run;
            in.k = t.origin[e.first];
            in.jump = t.origin[e.first] + e.count;
        } else if (in.op == Op::CullIfFar) {
            in.jump = entryOf[in.jump];
        }
        out.push_back(in);
    }
}

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
        // Room for the leaf tapes and the outside tape after them (addOutsideTape: the operands
        // and a guard and union per group); reserved, not touched.
        const size_t whole = tape.size();
        reserveLarge(m_out->instrs,
                     std::min(cells * std::min(whole, kLeafGuess), kMaxReserve) + 2 * whole + 64);
        FlatTape root;
        root.instrs.assign(tape.instructions().begin(), tape.instructions().end());
        root.folds.assign(tape.foldOperands().begin(), tape.foldOperands().end());
        root.origin.resize(root.instrs.size());
        std::iota(root.origin.begin(), root.origin.end(), 0u);
        m_whole = tape.instructions().data();
        int32_t memo = -1;
        const int first[3] = {0, 0, 0};
        node(root, memo, box, 0, first, range);
    }
    std::shared_ptr<PrunedTapes> finish() { return m_out; }
    // The mean instructions per leaf cell, against the whole tape's.
    double meanLeafInstrs() const {
        double sum = 0;
        for (uint32_t t : m_out->cellTape) sum += m_lengths[t];
        return sum / static_cast<double>(m_out->cellTape.size());
    }

  private:
    // One thread's: its pruner's scratch and the tape of each level of the subtree it descends.
    struct Local {
        PruneScratch scratch;
        std::vector<FlatTape> levels = std::vector<FlatTape>(kMaxLevels);
        CompactScratch compactScratch;
        std::vector<Instr> compact;  // a leaf tape in the form the cells keep (compactTape)
    };

    // The octree node over leaf cells first[a] + [0, range[a]), pruned from `parent` (whose leaf
    // id, once it has one, is `parentMemo`); it splits the axes at least half as long as its
    // longest, so that its cells stay about cubic.
    void node(const FlatTape& parent, int32_t& parentMemo, const Bounds3& box, int level,
              const int first[3], const int range[3]) {
        SDFT_CHECK(level < kMaxLevels);
        Local& local = m_locals.local();
        FlatTape own;  // the top levels' tapes; a subtree's live in its thread's levels
        FlatTape& mine = level < kParallelLevels ? own : local.levels[level];
        Pruner pruner(parent, m_consts, box, local.scratch);
        const bool changed = pruner.run();
        if (changed) pruner.emit(mine);
        const FlatTape& tape = changed ? mine : parent;
        int32_t ownMemo = -1;
        int32_t& memo = changed ? ownMemo : parentMemo;
        const Vec3 extent = box.extent();
        const float longest = maxComponent(extent);
        bool split[3];
        for (int a = 0; a < 3; ++a) split[a] = range[a] > 1 && extent[a] >= 0.5f * longest;
        // A cell farther than its diagonal from the surface (outside or inside) is not split:
        // rays cross it in a step or two, so a shorter tape would hardly be used.
        const float diagonal = length(extent);
        const Interval v = pruner.value();
        const bool far = v.lo > diagonal || v.hi < -diagonal;
        if (!(split[0] || split[1] || split[2]) || far || tape.instrs.size() <= kSmallTape) {
            const uint32_t id = leafId(local, tape, memo);
            const int* res = m_out->res;
            for (int z = first[2]; z < first[2] + range[2]; ++z)
                for (int y = first[1]; y < first[1] + range[1]; ++y)
                    std::fill_n(m_out->cellTape.begin() +
                                    (static_cast<size_t>(z) * res[1] + y) * res[0] + first[0],
                                range[0], id);
            return;
        }
        // Child c: bit a says which half along a split axis (0 along the others).
        auto child = [&](int c) {
            Bounds3 b = box;
            int f[3], r[3];
            for (int a = 0; a < 3; ++a) {
                f[a] = first[a];
                r[a] = range[a];
                const bool high = (c >> a) & 1;
                if (!split[a]) {
                    if (high) return;
                    continue;
                }
                r[a] = range[a] / 2;
                const float mid = 0.5f * (box.lo[a] + box.hi[a]);
                if (high) {
                    f[a] += r[a];
                    b.lo[a] = mid;
                } else {
                    b.hi[a] = mid;
                }
            }
            node(tape, memo, b, level + 1, f, r);
        };
        if (level < kParallelLevels) {
            tbb::parallel_for(0, 8, child);
        } else {
            for (int c = 0; c < 8; ++c) child(c);
        }
    }

    // The id of a leaf's tape: `memo`, or a new one for the tape, appended to the leaf tapes.
    uint32_t leafId(Local& local, const FlatTape& t, int32_t& memo) {
        {
            std::lock_guard<std::mutex> lock(m_mutex);
            if (memo >= 0) return static_cast<uint32_t>(memo);
        }
        compactTape(t, m_whole, local.compact, local.compactScratch);
        std::lock_guard<std::mutex> lock(m_mutex);
        if (memo >= 0) return static_cast<uint32_t>(memo);  // a sibling's, meanwhile
        std::vector<Instr>& all = m_out->instrs;
        memo = static_cast<int32_t>(m_lengths.size());
        m_lengths.push_back(static_cast<uint32_t>(t.instrs.size()));
        m_out->spans.push_back(static_cast<uint32_t>(all.size()));
        m_out->spans.push_back(static_cast<uint32_t>(local.compact.size()));
        all.insert(all.end(), local.compact.begin(), local.compact.end());
        return static_cast<uint32_t>(memo);
    }

    const float* m_consts;
    std::shared_ptr<PrunedTapes> m_out;
    tbb::enumerable_thread_specific<Local> m_locals;
    std::mutex m_mutex;
    const Instr* m_whole = nullptr;
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
Bounds3 cellBox(const Node& root) {
    Bounds3 box = nodeBounds(root);
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

std::shared_ptr<PrunedTapes> buildPrunedTapes(const Tape& tape, const Node& root) {
    size_t primitives = 0, folds = 0;
    for (const Instr& in : tape.instructions()) {
        primitives += in.op <= Op::Grid;
        folds += isCombine(in.op);
    }
    // Small tapes gain nothing from cells (their lookups cost more than they save).
    if (folds == 0 || tape.size() < kWorthPruning) return nullptr;
    Bounds3 box = cellBox(root);
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
