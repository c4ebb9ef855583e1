// The root refinement of sphere_tracer.h measured through the renderer: the depth AOV against
// exact ray intersections computed here in double precision, independently of the tape, on
// analytic scenes of spheres, boxes, capsules and a plane seen from a far, a close and a grazing
// camera, for the default tracer and the classic one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "sdftrace/math/camera.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"

namespace sdft {
namespace {

struct D3 {
    double x, y, z;
};
D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
D3 operator*(D3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
double len(D3 a) { return std::sqrt(dot(a, a)); }

// The scene, twice: as a scene file and as exact distance functions in double precision.
struct Sphere {
    D3 c;
    double r;
};
struct Box {
    D3 c, half;
};
struct Capsule {
    D3 a, b;
    double r;
};
const Sphere kSpheres[] = {{{0, 1, 0}, 1}, {{2.2, 0.5, 0.6}, 0.5}, {{-1.6, 0.35, 1.4}, 0.35}};
const Box kBoxes[] = {{{-2.2, 0.6, -0.8}, {0.5, 0.6, 0.7}}, {{1.4, 0.25, -1.6}, {0.9, 0.25, 0.4}}};
const Capsule kCapsules[] = {{{0.8, 0.3, 1.6}, {2.0, 1.4, 1.9}, 0.25},
                             {{-0.6, 0.2, -2.4}, {0.6, 0.2, -2.4}, 0.2}};

std::string v3(D3 v) {
    char b[96];
    std::snprintf(b, sizeof b, "[%.17g, %.17g, %.17g]", v.x, v.y, v.z);
    return b;
}

std::string sceneText(D3 eye, D3 target, double fov, const std::string& render) {
    std::string objects = R"({"type": "plane", "normal": [0, 1, 0]})";
    for (const Sphere& s : kSpheres)
        objects += R"(, {"type": "sphere", "radius": )" + std::to_string(s.r) +
                   R"(, "translate": )" + v3(s.c) + "}";
    for (const Box& b : kBoxes)
        objects += R"(, {"type": "box", "size": )" + v3(b.half * 2.0) + R"(, "translate": )" +
                   v3(b.c) + "}";
    for (const Capsule& c : kCapsules)
        objects += R"(, {"type": "capsule", "a": )" + v3(c.a) + R"(, "b": )" + v3(c.b) +
                   R"(, "radius": )" + std::to_string(c.r) + "}";
    return R"({"camera": {"eye": )" + v3(eye) + R"(, "target": )" + v3(target) + R"(, "fov": )" +
           std::to_string(fov) + R"(, "width": 240, "height": 160}, "objects": [)" + objects +
           R"(], "render": )" + render + "}";
}

double exactField(D3 p) {
    double f = p.y;
    for (const Sphere& s : kSpheres) f = std::min(f, len(p - s.c) - s.r);
    for (const Box& b : kBoxes) {
        const D3 q{std::fabs(p.x - b.c.x) - b.half.x, std::fabs(p.y - b.c.y) - b.half.y,
                   std::fabs(p.z - b.c.z) - b.half.z};
        const D3 o{std::max(q.x, 0.0), std::max(q.y, 0.0), std::max(q.z, 0.0)};
        f = std::min(f, len(o) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0));
    }
    for (const Capsule& c : kCapsules) {
        const D3 pa = p - c.a, ba = c.b - c.a;
        const double h = std::clamp(dot(pa, ba) / dot(ba, ba), 0.0, 1.0);
        f = std::min(f, len(pa - ba * h) - c.r);
    }
    return f;
}

// The first root along the ray: sphere tracing the exact distance down to 1e-12, then bisection
// on a bracket. Returns +inf on a miss.
double exactHit(D3 o, D3 d) {
    double t = 0;
    for (int i = 0; i < 100000 && t < 200; ++i) {
        const double f = exactField(o + d * t);
        if (f < 1e-12) {
            double lo = t - 1e-9, hi = t + 1e-9;
            while (exactField(o + d * hi) > 0) hi += 1e-9;
            for (int k = 0; k < 60; ++k) {
                const double mid = 0.5 * (lo + hi);
                (exactField(o + d * mid) > 0 ? lo : hi) = mid;
            }
            return 0.5 * (lo + hi);
        }
        t += f;
    }
    return INFINITY;
}

struct View {
    const char* name;
    D3 eye, target;
    double fov;
};
const View kViews[] = {{"far", {4, 4.5, 9}, {0, 0.5, 0}, 40},
                       {"close", {0.9, 1.6, 2.2}, {0, 0.9, 0}, 50},
                       {"grazing", {-7, 0.35, 5.5}, {1, 0.4, -1}, 35}};

struct Measured {
    int interior = 0, within = 0;
    double medianFootprints = 0, p99Footprints = 0;
    double evalsPerHit = 0;
};

// Depth errors of interior hit pixels (all 8 neighbours hit, none at a depth jump).
Measured measure(const View& v, const std::string& settings) {
    Scene scene = parseSceneText(sceneText(v.eye, v.target, v.fov, settings), "<exact hits>");
    Film film(scene.camera.width, scene.camera.height);
    render(planRender(scene), film);
    const Camera cam(scene.camera);
    const int w = film.width, h = film.height;
    std::vector<double> exact(film.pixels());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            // The camera's own float ray, in double from there on.
            const Ray r = cam.pixelRay(x, y);
            exact[y * w + x] = exactHit({r.origin.x, r.origin.y, r.origin.z},
                                        {r.direction.x, r.direction.y, r.direction.z});
        }
    const double footprint = 2.0 * cam.pixelRadius();  // a pixel's height at t = 1
    Measured m;
    std::vector<double> footprints;
    double evals = 0;
    int hits = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t p = static_cast<size_t>(y) * w + x;
            if (std::isfinite(film.depth[p])) {
                evals += film.steps[p];
                ++hits;
            }
            if (x == 0 || y == 0 || x == w - 1 || y == h - 1 || !std::isfinite(exact[p])) continue;
            bool interior = true;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const double n = exact[(y + dy) * w + x + dx];
                    interior =
                        interior && std::isfinite(n) && std::fabs(n - exact[p]) < 0.05 * exact[p];
                }
            if (!interior) continue;
            ++m.interior;
            const double err = std::fabs(film.depth[p] - exact[p]);
            m.within += err <= 1e-4 * exact[p];
            footprints.push_back(err / (footprint * exact[p]));
        }
    std::sort(footprints.begin(), footprints.end());
    if (!footprints.empty()) {
        m.medianFootprints = footprints[footprints.size() / 2];
        m.p99Footprints = footprints[footprints.size() * 99 / 100];
    }
    m.evalsPerHit = hits ? evals / hits : 0;
    return m;
}

TEST(ExactHits, DepthOnTheRootForTheDefaultAndTheClassicTracer) {
    struct Tracer {
        const char* name;
        std::string render;
    };
    const std::string classic =
        R"("omega": 1, "screen_space": false, "discontinuity_iterations": 0)";
    const Tracer tracers[] = {{"default", "{}"}, {"classic", "{" + classic + "}"}};
    for (const View& v : kViews)
        for (const Tracer& tr : tracers) {
            const std::string off = tr.render == "{}"
                                        ? R"({"root_iterations": 0})"
                                        : "{" + classic + R"(, "root_iterations": 0})";
            const Measured on = measure(v, tr.render), before = measure(v, off);
            ASSERT_GT(on.interior, 2000) << v.name;
            const double share = static_cast<double>(on.within) / on.interior;
            std::printf(
                "%-7s %-7s depth within 1e-4 t: %.2f%% of %d interior hits (without refinement "
                "%.2f%%); |dt| median %.4f, p99 %.4f footprints (without %.3f, %.3f); "
                "evaluations per hit ray %.2f (without %.2f)\n",
                v.name, tr.name, 100 * share, on.interior, 100.0 * before.within / before.interior,
                on.medianFootprints, on.p99Footprints, before.medianFootprints,
                before.p99Footprints, on.evalsPerHit, before.evalsPerHit);
            EXPECT_GE(share, 0.99) << v.name << " " << tr.name;
            EXPECT_LE(on.evalsPerHit, before.evalsPerHit + 2.0) << v.name << " " << tr.name;
        }
}

}  // namespace
}  // namespace sdft
