// 3D jump flooding (Tan et al. 2022, RTSDF §2.2; Rong and Tan 2006): passes with offsets N/2,
// N/4, ..., 1 in which every grid vertex adopts the nearest seed point among its 27 neighbours at
// the current offset. O(N^3 log N), parallel per pass; approximate where Voronoi regions are thin.
#pragma once

#include <vector>

#include "sdftrace/bake/surface_seeds.h"

namespace sdft {

enum class JfaVariant {
    Plain,       // offsets N/2 ... 1
    OnePlusJfa,  // an extra offset-1 pass first (Rong and Tan's 1+JFA)
    JfaPlusTwo,  // two extra passes, offsets 2 and 1, at the end (JFA+2)
};

struct JfaStats {
    std::vector<int> offsets;
    std::vector<double> passSeconds;  // one per offset
};

// The passes' offsets: N/2, N/4, ..., 1 for the grid's largest vertex count N, with the
// variant's extra passes.
std::vector<int> jumpFloodOffsets(const GridShape& shape, JfaVariant variant);

// Closest points propagated from `seeds` (kNoSeed in x: none).
std::vector<Vec3> jumpFlood(const GridShape& shape, std::vector<Vec3> seeds, JfaVariant variant,
                            int threads = 0, JfaStats* stats = nullptr);

}  // namespace sdft
