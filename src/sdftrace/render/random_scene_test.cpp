// Random small scene trees (random primitives, operators and transforms, fixed seeds): the tape
// keeps the Lipschitz bound it states, and rendering them gives no crash and no NaN or Inf pixel
// (issue 17's property test).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "sdftrace/field/node.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/field/test_util.h"
#include "sdftrace/render/renderer.h"

namespace sdft {
namespace {

using testing::Rng;

NodePtr randomPrimitive(Rng& rng) {
    const float s = rng.uniform(0.2f, 0.8f);
    switch (static_cast<int>(rng.uniform(0, 12))) {
        case 0:
            return node::sphere(s);
        case 1:
            return node::box({s, rng.uniform(0.1f, 0.8f), rng.uniform(0.1f, 0.8f)});
        case 2:
            return node::roundBox({s, s, s}, 0.3f * s);
        case 3:
            return node::torus(s, 0.3f * s);
        case 4:
            return node::capsule(rng.inCube(0.5f), rng.inCube(0.5f), 0.3f * s);
        case 5:
            return node::cylinder(s, rng.uniform(0.1f, 0.8f));
        case 6:
            return node::cone(s, rng.uniform(0.2f, 1.0f));
        case 7:
            return node::ellipsoid({s, rng.uniform(0.1f, 0.8f), rng.uniform(0.1f, 0.8f)});
        case 8:
            return node::octahedron(s);
        case 9:
            return node::dodecahedron(s);
        case 10:
            return node::blobs({{rng.inCube(0.3f), s, 1.0f}, {rng.inCube(0.3f), 0.8f * s, 0.7f}},
                               0.4f);
        default:
            return node::plane(rng.direction(), rng.uniform(0.5f, 1.5f));
    }
}

NodePtr randomTree(Rng& rng, int depth) {
    if (depth == 0 || rng.uniform(0, 1) < 0.25f) return randomPrimitive(rng);
    NodePtr a = randomTree(rng, depth - 1);
    switch (static_cast<int>(rng.uniform(0, 12))) {
        case 0:
            return node::unite({a, randomTree(rng, depth - 1), randomTree(rng, depth - 1)});
        case 1:
            return node::intersect({a, randomTree(rng, depth - 1)});
        case 2:
            return node::subtract(a, randomTree(rng, depth - 1));
        case 3:
            return node::smoothUnion(a, randomTree(rng, depth - 1), rng.uniform(0.01f, 0.4f));
        case 4:
            return node::smoothIntersection(a, randomTree(rng, depth - 1),
                                            rng.uniform(0.01f, 0.4f));
        case 5:
            return node::smoothDifference(a, randomTree(rng, depth - 1), rng.uniform(0.01f, 0.4f));
        case 6:
            return node::morph(a, randomTree(rng, depth - 1), rng.uniform(0, 1));
        case 7:
            return node::translate(a, rng.inCube(1));
        case 8:
            return node::rotate(a, rotationAxisAngle(rng.direction(), rng.uniform(0, 360)));
        case 9:
            return node::scale(a,
                               {rng.uniform(0.3f, 2), rng.uniform(0.3f, 2), rng.uniform(0.3f, 2)});
        case 10: {
            const Bounds3 b = nodeBounds(*a);
            if (!b.finite()) return a;
            const float reach = std::max(maxComponent(abs(b.lo)), maxComponent(abs(b.hi)));
            return node::repeat(a, Vec3(2.2f * reach),
                                {1, 0, rng.uniform(0, 1) < 0.5f ? 1.f : 0.f});
        }
        default:
            return node::displace(a, rng.uniform(0, 0.1f), rng.uniform(1, 4),
                                  static_cast<int>(rng.uniform(1, 4)), 0.5f);
    }
}

// The tree in one line, for failure messages: kind(params; children).
std::string describe(const Node& n) {
    std::string s = nodeKindName(n.kind);
    s += "(";
    for (size_t i = 0; i < n.params.size() && i < 8; ++i) {
        if (i) s += ",";
        s += std::to_string(n.params[i]).substr(0, 6);
    }
    for (const NodePtr& c : n.children) {
        s += "; ";
        s += describe(*c);
    }
    return s + ")";
}

// |f(p) - f(q)| <= L |p - q| for the tape's stated L, on random pairs near the surface and far.
TEST(RandomScenes, TapesKeepTheirLipschitzBound) {
    Rng rng(2026);
    const int trees =
        std::getenv("SDFT_RANDOM_TREES") ? std::atoi(std::getenv("SDFT_RANDOM_TREES")) : 60;
    for (int n = 0; n < trees; ++n) {
        const NodePtr root = randomTree(rng, 4);
        const Tape tape = compileTape(root, {.boundsCulling = false});
        const float L = tape.lipschitz();
        ASSERT_TRUE(std::isfinite(L) && L > 0) << "tree " << n;
        for (int i = 0; i < 400; ++i) {
            const Vec3 p = rng.inCube(2.5f);
            const Vec3 q = p + rng.direction() * rng.uniform(1e-3f, 0.5f);
            const float fp = tape.eval(p), fq = tape.eval(q);
            ASSERT_TRUE(std::isfinite(fp)) << "tree " << n;
            ASSERT_LE(std::fabs(fp - fq), L * length(p - q) * 1.001f + 1e-5f)
                << "tree " << n << " at " << p.x << "," << p.y << "," << p.z << ": "
                << describe(*root);
        }
    }
}

// Every pixel of every tree rendered through the default tracer, with soft shadows and AO, is
// finite.
TEST(RandomScenes, RenderWithoutNanOrInfPixels) {
    Rng rng(77);
    for (int n = 0; n < 24; ++n) {
        RenderPlan plan;
        plan.settings.shadowMethod = n % 2 ? ShadowMethod::Soft : ShadowMethod::Hard;
        plan.settings.ambientOcclusion = n % 3 == 0;
        plan.settings.threads = 1;
        compileField(plan, randomTree(rng, 4));
        plan.materials.push_back(Material{"default"});
        plan.lighting.lights.push_back(Light{});
        Light sphereLight;
        sphereLight.kind = Light::Kind::Sphere;
        sphereLight.position = {2, 3, 2};
        sphereLight.radius = 0.5f;
        plan.lighting.lights.push_back(sphereLight);
        plan.camera.eye = {rng.uniform(-3, 3), rng.uniform(0.5f, 3), rng.uniform(2, 4)};
        plan.camera.width = 24;
        plan.camera.height = 16;
        Film film(plan.camera.width, plan.camera.height);
        render(plan, film);
        for (float c : film.color) ASSERT_TRUE(std::isfinite(c)) << "tree " << n;
        for (float d : film.depth) ASSERT_FALSE(std::isnan(d)) << "tree " << n;
        for (float v : film.normal) ASSERT_TRUE(std::isfinite(v)) << "tree " << n;
    }
}

}  // namespace
}  // namespace sdft
