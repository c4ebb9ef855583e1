// Hierarchical Lipschitz pruning (tape_prune.h; Barbier et al., Eurographics 2025): the octree over
// the scene's box, each node's children pruned from its tape in one pass (prune_pass.h), the
// leaves' tapes compacted into Runs of the whole tape (prune_compact.h) by the thread that makes
// them, and the choice of whether the cells pay.
#include "sdftrace/field/tape_prune.h"

#include <sys/mman.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <mutex>
#include <new>
#include <numeric>
#include <span>
#include <utility>
#include <vector>

#include "sdftrace/field/prune_compact.h"
#include "sdftrace/field/prune_pass.h"

namespace sdft {

namespace {

using namespace prune;

std::atomic<LeafCompaction> g_leafCompaction{LeafCompaction::Lanes};

// The cells' box is the scene's (or its bounded operands') grown by this share of its diagonal;
// points outside it take the outside tape (PrunedTapes::outsideTape), which gives the same values
// at a higher cost per evaluation (a hierarchy over every operand), so the margin keeps the air
// just around the scene in cells.
constexpr float kOutsideMargin = 0.02f;

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
                            compactTape(tape, m_whole, mine, local.compactScratch);
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
