// Hierarchical Lipschitz pruning of a tape (Barbier, Sanchez, Paris et al., "Lipschitz Pruning:
// Hierarchical Simplification of Primitive-Based SDFs", Eurographics 2025): an octree over the
// scene's box whose cells each get the tape without the operands that cannot change the field
// inside the cell, every child pruned from its parent's tape
// (docs/decisions/0021-lipschitz-pruning.md).
#pragma once

#include <memory>
#include <vector>

#include "sdftrace/field/tape.h"

namespace sdft {

// A tape's instructions with the compiler's fold records (Tape::foldOperands), the form pruning
// reads and writes.
struct FlatTape {
    static constexpr uint32_t kMade = ~0u;  // origin: an instruction the pruning made (a copy)
    std::vector<Instr> instrs;
    std::vector<FoldOperands> folds;
    std::vector<uint32_t> origin;  // per instruction, its index in the whole tape, or kMade
};

// `tape` pruned for the points of `cell`: each fold operand whose value over the cell, bounded by
// its value at the cell's centre and the Lipschitz bound of its subtree, can never be the one
// that decides the fold is removed (hard union, intersection and difference), or whose blend
// weight is zero over the cell (smooth union, intersection and difference: |a - b| >= k). The
// result equals `tape`'s at every point of the cell (up to one rounding of a smooth blend's
// a + (b - a) at weight 1). Operands under a grid, a repetition or a displacement are kept.
// `changed` tells whether anything was removed.
FlatTape pruneTape(const FlatTape& tape, const float* consts, const Bounds3& cell, bool& changed);

// The cells' box is the scene's (or its bounded operands') grown by this share of its diagonal;
// points outside it take the outside tape (PrunedTapes::outsideTape), which gives the same values
// at a higher cost per evaluation (a hierarchy over every operand), so the margin keeps the air
// just around the scene in cells.
inline constexpr float kOutsideMargin = 0.02f;

// The octree's leaf cells and their tapes for a compiled tape, or null when pruning would not
// pay (no fold, a short tape, cells that keep most of it, or no finite box to put them in). A
// leaf tape keeps each stretch it shares with the whole tape as one Op::Run.
std::shared_ptr<PrunedTapes> buildPrunedTapes(const Tape& tape, const Node& root);

}  // namespace sdft
