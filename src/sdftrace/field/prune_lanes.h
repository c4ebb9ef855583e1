// The lanes of the pruning pass (tape_prune.h): a tape as pruning reads and writes it, the eight
// cells one pass prunes for, in vectors of eight floats, and what the pass decides for them.
// Internal to the pruning build (tape_prune.cpp and the headers it includes).
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "sdftrace/core/macros.h"
#include "sdftrace/field/tape.h"

namespace sdft::prune {

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

inline bool isCombine(Op op) { return op >= Op::Union && op <= Op::SmoothDifference; }
inline bool isHardCombine(Op op) { return op >= Op::Union && op <= Op::Difference; }
inline bool writesScalar(Op op) { return op != Op::CullIfFar && op < Op::Translate; }

// One pass over a parent's tape prunes it for up to this many cells at once (an octree node's
// children): each instruction is decoded once and bounded over every cell, lane by lane.
constexpr int kLanes = 8;
using LaneMask = uint8_t;  // bit l: lane l

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
inline Instr copyOf(Instr in) {
    in.op = Op::Copy;
    in.a = in.b;
    in.b = 0;
    in.cull = -1;
    return in;
}

// A kept guard's jump in lane l's pruned tape: past its (kept) operator. `next` is
// Pruner::emit's renumbering.
inline uint32_t laneJump(const uint32_t* next, uint32_t jump, int lane) {
    return next[(jump - 1) * kLanes + lane] + 1;
}

// What a pass decides for its cells: per instruction, the lanes that drop it and those that turn
// it into a copy of its second operand; per lane, the tape's values over the cell.
struct PruneResult {
    std::vector<LaneMask> drop, copy;
    Interval value[kLanes];
    LaneMask changed = 0;  // the lanes that drop anything
    LaneMask copied = 0;   // the lanes that turn anything into a copy
};

}  // namespace sdft::prune
