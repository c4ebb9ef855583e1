#include "sdftrace/render/horizon.h"

#include <cmath>

namespace sdft {

HorizonPlanes horizonPlanes(const NodePtr& root) {
    HorizonPlanes h;
    for (const NodePtr& n : topLevelObjects(root)) {
        if (n->kind == NodeKind::Plane && n->params.size() >= 4) {
            if (h.count == HorizonPlanes::kMax) return {};
            const float* k = n->params.data();
            const float norm = std::sqrt(k[0] * k[0] + k[1] * k[1] + k[2] * k[2]);
            if (!(norm > 0) || !std::isfinite(norm) || !std::isfinite(k[3])) return {};
            for (int c = 0; c < 4; ++c) h.plane[h.count][c] = k[c] / norm;
            ++h.count;
            continue;
        }
        const Bounds3 b = nodeBounds(*n);
        if (b.empty()) continue;
        if (!b.finite()) return {};  // something else unbounded: no horizon beyond it
        h.rest = unite(h.rest, b);
    }
    return h;
}

}  // namespace sdft
