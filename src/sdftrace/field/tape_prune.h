// Hierarchical Lipschitz pruning of a tape (Barbier, Sanchez, Paris et al., "Lipschitz Pruning:
// Hierarchical Simplification of Primitive-Based SDFs", Eurographics 2025): an octree over the
// scene's box whose cells each get the tape without the operands that cannot change the field
// inside the cell, every child pruned from its parent's tape
// (docs/decisions/0021-lipschitz-pruning.md).
#pragma once

#include <memory>

#include "sdftrace/field/tape.h"

namespace sdft {

// The octree's leaf cells and their tapes for a compiled tape, or null when pruning would not
// pay (no fold, a short tape, cells that keep most of it, a few big operands that bounds culling
// already skips, or no finite box to put them in). A leaf tape keeps each stretch it shares with
// the whole tape as one Op::Run.
std::shared_ptr<PrunedTapes> buildPrunedTapes(const Tape& tape, const Node& root);

// How the leaf cells' tapes are made: for all the leaf children of a node in one walk over its tape
// (the default), or each child pruned into a tape of its own first and compacted from that (the
// plain way, which tests hold the other to). Returns the previous way.
enum class LeafCompaction { Lanes, OneByOne };
LeafCompaction setLeafCompaction(LeafCompaction way);

// Whether buildPrunedTapes may find cells worth their lookups (a tape long enough, with a fold);
// false means it returns null at once.
bool mayPrune(const Tape& tape);

}  // namespace sdft
