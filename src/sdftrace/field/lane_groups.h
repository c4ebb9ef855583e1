// A batch's lanes grouped by the pruned tape of their cell (TapeCells::tapeOf), one group at a
// time: the batch evaluators (Tape::evalBatch, evalSegmentBatch) gather a group's lanes, evaluate
// them with the group's tape and scatter the results back.
#pragma once

#include <cstdint>

#include "sdftrace/field/tape_view.h"

namespace sdft {

// The lanes of laneTape[from]'s tape among lanes [from, n), in order[0 .. m), marked done in
// laneTape; returns m, or 0 when lane `from` is done already. Call it for from = 0 .. n - 1.
inline int takeLaneGroup(uint32_t* laneTape, int from, int n, uint32_t* order, uint32_t& tape) {
    constexpr uint32_t kDone = TapeCells::kWhole - 1;
    tape = laneTape[from];
    if (tape == kDone) return 0;
    int m = 0;
    for (int l = from; l < n; ++l) {
        if (laneTape[l] != tape) continue;
        order[m++] = static_cast<uint32_t>(l);
        laneTape[l] = kDone;
    }
    return m;
}

}  // namespace sdft
