// Helpers shared by the field tests: a fixed-seed RNG, a tree using every node kind, and a grid
// view without its empty-space skipping.
#pragma once

#include <random>

#include "sdftrace/field/grid.h"
#include "sdftrace/field/node.h"

namespace sdft::testing {

class Rng {
  public:
    explicit Rng(uint32_t seed) : m_gen(seed) {}
    float uniform(float lo, float hi) {
        return std::uniform_real_distribution<float>(lo, hi)(m_gen);
    }
    Vec3 inBox(Vec3 lo, Vec3 hi) {
        return {uniform(lo.x, hi.x), uniform(lo.y, hi.y), uniform(lo.z, hi.z)};
    }
    Vec3 inCube(float h) { return inBox(Vec3(-h), Vec3(h)); }
    Vec3 direction() {
        for (;;) {
            Vec3 v = inCube(1);
            float l = length(v);
            if (l > 1e-3f && l <= 1) return v / l;
        }
    }

  private:
    std::mt19937 m_gen;
};

// One tree with every primitive, operator and transform, for tape-vs-tree and Lipschitz tests.
inline NodePtr everyKindTree() {
    using namespace node;
    NodePtr blobby = blobs({{{0, 0, 0}, 0.6f, 1.0f}, {{0.4f, 0.1f, 0}, 0.5f, 0.8f}}, 0.4f);
    NodePtr a =
        smoothUnion(translate(sphere(0.5f), {-1, 0, 0}), roundBox({0.4f, 0.3f, 0.5f}, 0.1f), 0.3f);
    NodePtr b = smoothIntersection(box({0.6f, 0.6f, 0.6f}), sphere(0.75f), 0.1f);
    NodePtr c =
        smoothDifference(torus(0.6f, 0.2f), capsule({-0.5f, 0, 0}, {0.5f, 0.2f, 0}, 0.15f), 0.05f);
    NodePtr d = subtract(cylinder(0.4f, 0.5f), cone(0.3f, 0.8f));
    NodePtr e = morph(ellipsoid({0.6f, 0.3f, 0.4f}), octahedron(0.5f), 0.3f);
    NodePtr f = intersect({dodecahedron(0.5f), complement(sphere(0.2f))});
    NodePtr g = displace(scale(blobby, {1.5f, 0.8f, 1.0f}), 0.05f, 3.0f, 2, 0.5f);
    NodePtr h = repeat(sphere(0.2f), {0.7f, 0.7f, 0.7f}, {2, 0, 1});
    NodePtr rotated = rotate(translate(c, {0, 1.5f, 0}), rotationAxisAngle({1, 1, 0}, 35));
    return unite({translate(a, {0, 0, 2}), b, rotated, translate(d, {2, 0, 0}),
                  translate(e, {-2, 0, 0}), translate(f, {0, -2, 0}), translate(g, {0, 2.5f, -2}),
                  translate(h, {0, 0, -3}), plane({0, 1, 0}, 3.0f)});
}

// The same view without empty-space skipping (the plain block traversal).
inline GridView withoutSkipping(GridView v) {
    v.blockSkip = nullptr;
    v.tileSkip = nullptr;
    return v;
}

}  // namespace sdft::testing
