// The shape of a dense grid read from a file that states samples per axis, an origin and a
// spacing (SDFGen's .sdf, raw float32 with a sidecar): validated, with the memory it needs checked
// against the budget before the samples are read. Internal to io.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>

#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/field/grid.h"

namespace sdft::io_detail {

constexpr int64_t kMaxDenseSamplesPerAxis = 32769;  // 32768 cells, as .sdfg

inline GridShape denseShape(const int64_t dims[3], const double origin[3], double spacing,
                            const std::string& where) {
    GridShape s;
    for (int a = 0; a < 3; ++a) {
        if (dims[a] < 2 || dims[a] > kMaxDenseSamplesPerAxis) {
            throw InputError(where + ": " + std::to_string(dims[0]) + "x" +
                             std::to_string(dims[1]) + "x" + std::to_string(dims[2]) +
                             " samples is out of range (accepted: 2 to " +
                             std::to_string(kMaxDenseSamplesPerAxis) + " per axis)");
        }
        if (!(std::fabs(origin[a]) <= kMaxCoordinate))
            throw InputError(where + ": origin must be finite numbers within +-1e9");
        s.cells[a] = static_cast<int>(dims[a] - 1);
        s.origin[a] = static_cast<float>(origin[a]);
    }
    if (!(spacing > 0) ||
        !(spacing * static_cast<double>(dims[0] + dims[1] + dims[2]) <= kMaxCoordinate))
        throw InputError(where + ": the spacing must be a positive number (the grid within +-1e9)");
    s.voxelSize = static_cast<float>(spacing);
    checkMemoryBudget(2.0 * sizeof(float) * static_cast<double>(s.vertexCount()), where,
                      "the grid's " + std::to_string(s.vertexCount()) + " samples",
                      "resample it coarser");
    return s;
}

}  // namespace sdft::io_detail
