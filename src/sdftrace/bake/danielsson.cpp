#include "sdftrace/bake/danielsson.h"

#include <array>

namespace sdft {

std::vector<Vec3> danielssonTransform(const GridShape& s, std::vector<Vec3> seed) {
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    auto at = [&](int i, int j, int k) { return (static_cast<size_t>(k) * vy + j) * vx + i; };
    // The 13 neighbours that precede a vertex in x-fastest raster order; the backward sweep uses
    // their negations.
    std::vector<std::array<int, 3>> before;
    for (int dk = -1; dk <= 0; ++dk)
        for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di)
                if (dk < 0 || (dk == 0 && (dj < 0 || (dj == 0 && di < 0))))
                    before.push_back({di, dj, dk});
    auto relax = [&](int i, int j, int k, int sign) {
        Vec3 p = s.origin + Vec3(i, j, k) * s.voxelSize;
        Vec3& best = seed[at(i, j, k)];
        float bestD = best.x == kNoSeed ? kNoSeed : dot(p - best, p - best);
        for (const auto& o : before) {
            int ii = i + sign * o[0], jj = j + sign * o[1], kk = k + sign * o[2];
            if (ii < 0 || jj < 0 || kk < 0 || ii >= vx || jj >= vy || kk >= vz) continue;
            Vec3 q = seed[at(ii, jj, kk)];
            if (q.x == kNoSeed) continue;
            float d = dot(p - q, p - q);
            if (d < bestD) bestD = d, best = q;
        }
    };
    for (int k = 0; k < vz; ++k)
        for (int j = 0; j < vy; ++j)
            for (int i = 0; i < vx; ++i) relax(i, j, k, 1);
    for (int k = vz - 1; k >= 0; --k)
        for (int j = vy - 1; j >= 0; --j)
            for (int i = vx - 1; i >= 0; --i) relax(i, j, k, -1);
    return seed;
}

}  // namespace sdft
