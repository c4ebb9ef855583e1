// Hierarchical Lipschitz pruning (tape_prune.h; Barbier et al., Eurographics 2025): interval bounds
// of every instruction over a cell from the value at its centre and the Lipschitz bound of the
// primitives (every primitive is 1-Lipschitz; a point transform scales that by its stretch),
// propagated through the CSG operators; folds drop the operands those bounds rule out.
#include "sdftrace/field/tape_prune.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <unordered_map>

#include "sdftrace/field/tape_view.h"

namespace sdft {

namespace {

struct Interval {
    float lo = -kInfinity, hi = kInfinity;
};

bool isCombine(Op op) { return op >= Op::Union && op <= Op::SmoothDifference; }
bool isHardCombine(Op op) { return op >= Op::Union && op <= Op::Difference; }
bool writesScalar(Op op) { return op != Op::CullIfFar && op < Op::Translate; }

// The interval of a binary op's result from its operands' (operators.h: the polynomial smooth
// minimum lies within k/4 below the minimum).
Interval combine(Op op, Interval a, Interval b, const float* k) {
    const float blend = k[0] > 0 ? 0.25f * k[0] : 0.0f;
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

class Pruner {
  public:
    Pruner(const FlatTape& t, const float* consts, const Bounds3& cell)
        : m_t(t), m_k(consts), m_n(t.instrs.size()) {
        m_centre = (cell.lo + cell.hi) * 0.5f;
        m_radius = 0.5f * length(cell.hi - cell.lo);
        m_out.resize(m_n);
        m_accDef.assign(m_n, -1);
        m_rhsDef.assign(m_n, -1);
        m_drop.assign(m_n, 0);
        m_copy.assign(m_n, 0);
    }
    FlatTape run(bool& changed) {
        bounds();
        decideHard();
        decideSmooth();
        changed = std::find(m_drop.begin(), m_drop.end(), 1) != m_drop.end();
        return changed ? emit() : FlatTape{};
    }

  private:
    // Forward pass: every scalar instruction's interval over the cell.
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
                m_accDef[i] = writer[in.a];
                m_rhsDef[i] = writer[in.b];
                r = combine(op, sr[in.a], sr[in.b], k);
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
            m_out[i] = r;
            if (writesScalar(op)) {
                sr[in.out] = r;
                writer[in.out] = static_cast<int32_t>(i);
            }
        }
    }

    // Hard folds, as chains of one operator through the accumulator (min, max and max(a, -b)
    // are associative, so nested folds of the same operator form one chain): an operand whose
    // values over the cell all lie beyond the best bound another operand guarantees never
    // decides the result.
    void decideHard() {
        std::vector<int32_t> chainOf(m_n, -1);
        struct Chain {
            Op op;
            int32_t first;
            std::vector<int32_t> members;
        };
        std::vector<Chain> chains;
        for (size_t i = 0; i < m_n; ++i) {
            const Op op = m_t.instrs[i].op;
            if (!isHardCombine(op)) continue;
            const int32_t j = m_accDef[i];
            if (j >= 0 && m_t.instrs[j].op == op && chainOf[j] >= 0) {
                chainOf[i] = chainOf[j];
            } else {
                chainOf[i] = static_cast<int32_t>(chains.size());
                chains.push_back({op, j, {}});
            }
            chains[chainOf[i]].members.push_back(static_cast<int32_t>(i));
        }
        for (const Chain& c : chains) decideChain(c.op, c.first, c.members);
    }

    void decideChain(Op op, int32_t first, const std::vector<int32_t>& members) {
        if (first < 0) return;
        // The operands' intervals as the fold sees them (a difference negates all but the first).
        for (int32_t m : members)
            if (m_rhsDef[m] < 0) return;
        auto operand = [&](int32_t m) {
            const Interval b = m_out[m_rhsDef[m]];
            return op == Op::Difference ? Interval{-b.hi, -b.lo} : b;
        };
        const bool isMin = op == Op::Union;
        float best = isMin ? m_out[first].hi : m_out[first].lo;
        for (int32_t m : members)
            best = isMin ? std::min(best, operand(m).hi) : std::max(best, operand(m).lo);
        auto ruledOut = [&](Interval v) { return isMin ? v.lo > best : v.hi < best; };
        for (int32_t m : members)
            if (ruledOut(operand(m))) dropOperand(m);
        // The first operand: the first member left takes its place (a copy of its operand); a
        // difference's first operand is never negated, so it stays.
        if (op == Op::Difference || !ruledOut(m_out[first])) return;
        for (int32_t m : members) {
            if (m_drop[m]) continue;
            dropRange(m_t.folds[members.front()].fold, first);
            if (m_t.instrs[m].cull >= 0) m_drop[m_t.folds[m].operand - 1] = 1;
            m_copy[m] = 1;
            return;
        }
    }

    // Smooth folds, operand by operand: zero blend weight over the whole cell (|a - b| >= k,
    // the right sign) leaves the accumulator as it was.
    void decideSmooth() {
        for (size_t i = 0; i < m_n; ++i) {
            const Instr& in = m_t.instrs[i];
            if (!isCombine(in.op) || isHardCombine(in.op)) continue;
            const float k = m_k[in.k];
            if (!(k > 0) || m_accDef[i] < 0 || m_rhsDef[i] < 0) continue;
            const float margin = k * (1 + 1e-5f);
            const Interval a = m_out[m_accDef[i]], b = m_out[m_rhsDef[i]];
            const bool inactive = in.op == Op::SmoothUnion          ? b.lo - a.hi >= margin
                                  : in.op == Op::SmoothIntersection ? a.lo - b.hi >= margin
                                                                    : a.lo + b.lo >= margin;
            if (inactive) dropOperand(static_cast<int32_t>(i));
        }
    }

    // A fold member and its operand, with the operand's guard.
    void dropOperand(int32_t m) {
        const uint32_t from = m_t.folds[m].operand - (m_t.instrs[m].cull >= 0 ? 1 : 0);
        dropRange(from, static_cast<uint32_t>(m));
    }
    void dropRange(uint32_t from, uint32_t to) {
        std::fill(m_drop.begin() + from, m_drop.begin() + to + 1, 1);
    }

    // The kept instructions, renumbered: jumps, fold records, copies.
    FlatTape emit() {
        std::vector<uint32_t> next(m_n + 1);  // new index of the first kept instruction >= i
        uint32_t kept = 0;
        for (size_t i = 0; i < m_n; ++i) kept += !m_drop[i];
        next[m_n] = kept;
        for (size_t i = m_n; i-- > 0;) next[i] = next[i + 1] - (m_drop[i] ? 0 : 1);
        FlatTape out;
        out.instrs.reserve(kept);
        out.folds.reserve(kept);
        for (size_t i = 0; i < m_n; ++i) {
            if (m_drop[i]) continue;
            Instr in = m_t.instrs[i];
            FoldOperands f{};
            if (m_copy[i]) {
                in.op = Op::Copy;
                in.a = in.b;
                in.b = 0;
                in.cull = -1;
            } else if (in.op == Op::CullIfFar) {
                in.jump = next[in.jump - 1] + 1;  // past its (kept) operator
            } else if (isCombine(in.op)) {
                f = {next[m_t.folds[i].operand], next[m_t.folds[i].fold]};
            }
            out.instrs.push_back(in);
            out.folds.push_back(f);
        }
        return out;
    }

    const FlatTape& m_t;
    const float* m_k;
    size_t m_n;
    Vec3 m_centre;
    float m_radius = 0;
    std::vector<Interval> m_out;
    std::vector<int32_t> m_accDef, m_rhsDef;
    std::vector<uint8_t> m_drop, m_copy;
};

// A leaf tape stops at this many instructions: its cells share it.
constexpr size_t kSmallTape = 12;
// Tapes shorter than this are not pruned, nor those whose cells keep on average more than this
// share of the instructions.
constexpr size_t kWorthPruning = 48;
constexpr double kWorthwhileShare = 0.5;

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
        m_out->cellTape.assign(static_cast<size_t>(range[0]) * range[1] * range[2], 0);
        auto root = std::make_shared<FlatTape>();
        root->instrs.assign(tape.instructions().begin(), tape.instructions().end());
        root->folds.assign(tape.foldOperands().begin(), tape.foldOperands().end());
        const int first[3] = {0, 0, 0};
        node(root, box, 0, first, range);
    }
    std::shared_ptr<PrunedTapes> finish() {
        for (const auto& t : m_tapes) {
            m_out->spans.push_back(static_cast<uint32_t>(m_out->instrs.size()));
            m_out->spans.push_back(static_cast<uint32_t>(t->instrs.size()));
            m_out->instrs.insert(m_out->instrs.end(), t->instrs.begin(), t->instrs.end());
        }
        return m_out;
    }
    // The mean instructions per leaf cell, against the whole tape's.
    double meanLeafInstrs() const {
        double sum = 0;
        for (uint32_t t : m_out->cellTape) sum += static_cast<double>(m_tapes[t]->instrs.size());
        return sum / static_cast<double>(m_out->cellTape.size());
    }

  private:
    // The octree node over leaf cells first[a] + [0, range[a]), pruned from `parent`; it splits
    // the axes at least half as long as its longest, so that its cells stay about cubic.
    void node(const std::shared_ptr<const FlatTape>& parent, const Bounds3& box, int level,
              const int first[3], const int range[3]) {
        bool changed = false;
        FlatTape pruned = pruneTape(*parent, m_consts, box, changed);
        const std::shared_ptr<const FlatTape> tape =
            changed ? std::make_shared<const FlatTape>(std::move(pruned)) : parent;
        const Vec3 extent = box.extent();
        const float longest = maxComponent(extent);
        bool split[3];
        for (int a = 0; a < 3; ++a) split[a] = range[a] > 1 && extent[a] >= 0.5f * longest;
        if (!(split[0] || split[1] || split[2]) || tape->instrs.size() <= kSmallTape) {
            const uint32_t id = tapeId(tape);
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
            node(tape, b, level + 1, f, r);
        };
        if (level < 2) {
            tbb::parallel_for(0, 8, child);
        } else {
            for (int c = 0; c < 8; ++c) child(c);
        }
    }
    uint32_t tapeId(const std::shared_ptr<const FlatTape>& t) {
        std::lock_guard<std::mutex> lock(m_mutex);
        auto [it, added] = m_ids.try_emplace(t.get(), static_cast<uint32_t>(m_tapes.size()));
        if (added) m_tapes.push_back(t);
        return it->second;
    }

    const float* m_consts;
    std::shared_ptr<PrunedTapes> m_out;
    std::mutex m_mutex;
    std::vector<std::shared_ptr<const FlatTape>> m_tapes;
    std::unordered_map<const FlatTape*, uint32_t> m_ids;
};

// The box the cells cover: the scene's bounds, or (a top-level union with planes) those of its
// bounded operands; grown by a margin, which the outside tape's bound steps over (tape_prune.h).
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
    return box.expanded(kOutsideMargin * length(box.extent()) + 1e-6f);
}

}  // namespace

FlatTape pruneTape(const FlatTape& tape, const float* consts, const Bounds3& cell, bool& changed) {
    return Pruner(tape, consts, cell).run(changed);
}

std::shared_ptr<PrunedTapes> buildPrunedTapes(const Tape& tape, const Node& root) {
    size_t primitives = 0, folds = 0;
    for (const Instr& in : tape.instructions()) {
        primitives += in.op <= Op::Grid;
        folds += isCombine(in.op);
    }
    // Small tapes gain nothing from cells (their lookups cost more than they save).
    if (folds == 0 || tape.size() < kWorthPruning) return nullptr;
    const Bounds3 box = cellBox(root);
    if (box.empty()) return nullptr;
    // About one leaf cell per primitive along the longest axis, 2 to 64 cells.
    const double perAxis = std::cbrt(static_cast<double>(primitives));
    const int levels = std::clamp(static_cast<int>(std::lround(std::log2(perAxis))) + 1, 1, 6);
    Builder builder(tape, box, maxComponent(box.extent()) / static_cast<float>(1 << levels));
    // Cells whose tapes are not much shorter than the whole are not worth their lookups.
    if (builder.meanLeafInstrs() > kWorthwhileShare * static_cast<double>(tape.size()))
        return nullptr;
    return builder.finish();
}

}  // namespace sdft
