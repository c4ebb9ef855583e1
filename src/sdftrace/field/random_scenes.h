// Random scenes of many small CSG groups (every hard and smooth operator, several primitives,
// scaled and rotated ones) over a plane: the tests of pruning and of segment bounds use them.
#pragma once

#include <cmath>
#include <vector>

#include "sdftrace/field/node.h"
#include "sdftrace/field/test_util.h"

namespace sdft::testing {

inline NodePtr randomLeaf(Rng& rng, float spread) {
    const float s = rng.uniform(0.05f, 0.3f);
    NodePtr p;
    switch (static_cast<int>(rng.uniform(0, 6))) {
        case 0:
            p = node::sphere(s);
            break;
        case 1:
            p = node::box({s, rng.uniform(0.05f, 0.3f), s});
            break;
        case 2:
            p = node::torus(s, 0.3f * s);
            break;
        case 3:
            p = node::capsule(rng.inCube(0.2f), rng.inCube(0.2f), 0.4f * s);
            break;
        case 4:
            p = node::scale(node::sphere(s), {rng.uniform(0.5f, 2), 1, rng.uniform(0.5f, 2)});
            break;
        default:
            p = node::rotate(node::cylinder(s, 2 * s),
                             rotationAxisAngle(rng.direction(), rng.uniform(0, 360)));
    }
    return node::translate(p, rng.inBox({-spread, 0, -spread}, {spread, 1, spread}));
}

// A group of a few leaves under one operator (every hard and smooth CSG operator).
inline NodePtr randomGroup(Rng& rng, float spread) {
    const Vec3 at = rng.inBox({-spread, 0, -spread}, {spread, 0.5f, spread});
    auto leaf = [&] { return node::translate(randomLeaf(rng, 0.3f), at); };
    const float k = rng.uniform(0.02f, 0.2f);
    switch (static_cast<int>(rng.uniform(0, 6))) {
        case 0:
            return node::unite({leaf(), leaf(), leaf()});
        case 1:
            return node::smoothUnion(node::smoothUnion(leaf(), leaf(), k), leaf(), k);
        case 2:
            return node::intersect({leaf(), node::translate(node::sphere(0.4f), at)});
        case 3:
            return node::subtract(leaf(), node::unite({leaf(), leaf()}));
        case 4:
            return node::smoothIntersection(leaf(), node::translate(node::sphere(0.35f), at), k);
        default:
            return node::smoothDifference(leaf(), leaf(), k);
    }
}

inline NodePtr randomScene(Rng& rng, int groups, bool plane) {
    std::vector<NodePtr> c;
    if (plane) c.push_back(node::plane({0, 1, 0}, 0.1f));
    const float spread = 0.6f * std::sqrt(static_cast<float>(groups));
    for (int i = 0; i < groups; ++i) c.push_back(randomGroup(rng, spread));
    return node::unite(c);
}

}  // namespace sdft::testing
