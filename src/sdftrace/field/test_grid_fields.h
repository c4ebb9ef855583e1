// Fields for the grid tests (CPU and GPU): grid shapes of any cell counts over [-1, 1] along their
// longest axis, a bumpy sphere sampled at their vertices, and a sparse grid's own block table.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "sdftrace/field/grid.h"

namespace sdft::testing {

// A sparse grid's two-level block table, as the builder takes it.
inline BlockTable tableOf(const Grid& g) {
    BlockTable t;
    const GridView v = g.view();
    for (int a = 0; a < 3; ++a) t.blocks[a] = v.blocks[a], t.tiles[a] = v.tiles[a];
    t.tilePage = g.tilePage();
    t.flags = g.flags();
    return t;
}

inline GridShape shapeOverUnitCube(int nx, int ny, int nz) {
    GridShape s;
    s.cells[0] = nx, s.cells[1] = ny, s.cells[2] = nz;
    s.origin = Vec3(-1.0f);
    s.voxelSize = 2.0f / static_cast<float>(std::max(nx, std::max(ny, nz)));
    return s;
}

// A sphere of radius r around c with sine bumps of amplitude `bumps`, world units, x fastest.
inline std::vector<float> bumpySphere(const GridShape& s, Vec3 c, float r, float bumps) {
    std::vector<float> out;
    out.reserve(s.vertexCount());
    for (int k = 0; k <= s.cells[2]; ++k)
        for (int j = 0; j <= s.cells[1]; ++j)
            for (int i = 0; i <= s.cells[0]; ++i) {
                const Vec3 p = s.origin + Vec3(i, j, k) * s.voxelSize;
                out.push_back(length(p - c) - r +
                              bumps * std::sin(7 * p.x) * std::sin(5 * p.y) * std::sin(6 * p.z));
            }
    return out;
}

}  // namespace sdft::testing
