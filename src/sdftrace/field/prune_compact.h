// Leaf tapes as the pruned cells keep them (tape_prune.h): each stretch a pruned tape shares with
// the whole tape as one Op::Run, from a leaf's own tape (compactTape) or, for all the leaf
// children of a node at once, from its tape and the pass's decisions (LaneCompactor). Internal
// to the pruning build.
#pragma once

#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "sdftrace/exec/simd.h"
#include "sdftrace/field/prune_lanes.h"

namespace sdft::prune {

// compactTape's working memory, one per thread.
struct CompactScratch {
    struct Entry {
        uint32_t first, count;  // instructions of the pruned tape: a Run when count > 1
    };
    std::vector<uint8_t> copied, starts;
    std::vector<uint32_t> entryOf;
    std::vector<Entry> entries;
};

// The entry of a leaf tape that stands for the whole tape's `count` instructions from `first`.
inline Instr runOf(uint32_t first, uint32_t count) {
    Instr run{};
    run.op = Op::Run;
    run.k = first;
    run.jump = first + count;
    return run;
}

// A pruned tape as the cells keep it, appended to `out`: each stretch of instructions that the
// whole tape has as they are (consecutive there, every jump inside) becomes one Op::Run of the
// whole tape's instructions, and the rest is copied, its jumps renumbered. `whole` is the whole
// tape's.
inline void compactTape(const FlatTape& t, const Instr* whole, std::vector<Instr>& out,
                        CompactScratch& scratch) {
    const size_t n = t.instrs.size();
    const std::vector<uint32_t>& origin = t.origin;
    auto verbatim = [&](size_t j) { return origin[j] != FlatTape::kMade; };
    auto follows = [&](size_t j) {  // j continues j - 1's stretch of the whole tape
        return j > 0 && verbatim(j) && verbatim(j - 1) && origin[j] == origin[j - 1] + 1;
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
        if (t.instrs[j].op != Op::CullIfFar) continue;
        const uint32_t jump = t.instrs[j].jump;
        bool intact = jump - j == whole[origin[j]].jump - origin[j];
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
        if (e.count > 1) {
            out.push_back(runOf(origin[e.first], e.count));
            continue;
        }
        Instr in = t.instrs[e.first];
        if (in.op == Op::CullIfFar) in.jump = entryOf[in.jump];
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
            c.out.push_back(runOf(end - count, count));
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

}  // namespace sdft::prune
