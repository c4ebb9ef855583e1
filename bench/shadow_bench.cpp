// Soft shadows three ways against the ground truth, in one run (issue 5; RTSDF fig. 14): SDF soft
// shadows (RTSDF's estimate with and without Aaltonen's triangulation, and the centred one; with
// the scene's max step of 0.05 as RTSDF §2.5.2, and without),
// shadow maps (PCF, EVSM 15 x 15) and hard shadows, against distributed ray tracing with many
// rays per point (a few-ray distributed render is listed too). The scene is examples/shadows.json:
// a floor, a thick box, a thin plate on a thin pole and a plant of thin stems and leaves under a
// sphere light.
//
// Per method: the render's time (median of --reps, shadow maps built inside it), shadow
// evaluations per pixel, and the error of the `shadow` AOV (the light's visibility) against the
// ground truth: RMSE and max over the shadowed region (pixels facing the light where either is
// below 0.99).
//
//   build/release/bench/sdftrace_shadow_bench [--width 480 --height 300 --reps 5 --truth 1024
//       --threads 2]
//
// Prints a markdown table on stdout.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bench_flags.h"
#include "sdftrace/math/camera.h"
#include "sdftrace/render/light_sample.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"

using namespace sdft;

namespace {

struct Method {
    const char* name;
    ShadowMethod method;
    int rays = 0;
    bool centered = true, triangulate = true;
    float maxStep = -1;  // soft: the scene's (0.05) unless set
};

struct Run {
    double ms = 0;
    std::vector<float> shadow, depth, normal;
    double evaluationsPerPixel = 0;
};

Run renderWith(const Scene& base, const Method& m, int reps) {
    Scene scene = base;
    scene.settings.shadowMethod = m.method;
    if (m.rays) scene.settings.shadowRays = m.rays;
    scene.settings.soft.centered = m.centered;
    scene.settings.soft.triangulate = m.triangulate;
    if (m.maxStep >= 0) scene.settings.soft.maxStep = m.maxStep;
    const RenderPlan plan = planRender(scene);
    Run run;
    std::vector<double> times;
    for (int i = 0; i < reps; ++i) {
        Film film(scene.camera.width, scene.camera.height);
        auto t0 = std::chrono::steady_clock::now();
        RenderStats st = render(plan, film);
        times.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
        run.shadow = film.shadow;
        run.depth = film.depth;
        run.normal = film.normal;
        run.evaluationsPerPixel = double(st.shadowEvaluations) / double(film.pixels());
    }
    std::sort(times.begin(), times.end());
    run.ms = times[times.size() / 2];
    return run;
}

}  // namespace

int main(int argc, char** argv) {
    int width = 480, height = 300, reps = 5, truthRays = 1024, threads = 2;
    constexpr const char* kUsage =
        "usage: sdftrace_shadow_bench [--width 480] [--height 300] [--reps 5] [--truth 1024]\n"
        "       [--threads 2]\n";
    if (const int status = bench::checkFlagPairs(argc, argv, kUsage); status >= 0) return status;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string k = argv[i];
        const int v = bench::intFlag(k, argv[i + 1]);
        if (k == "--width")
            width = v;
        else if (k == "--height")
            height = v;
        else if (k == "--reps")
            reps = v;
        else if (k == "--truth")
            truthRays = v;
        else if (k == "--threads")
            threads = v;
        else {
            std::fprintf(stderr, "unknown option %s\n", k.c_str());
            return 2;
        }
    }
    Scene scene = parseSceneFile(std::string(SDFT_SOURCE_DIR) + "/examples/shadows.json");
    scene.camera.width = width;
    scene.camera.height = height;
    scene.settings.threads = threads;

    const Run truth =
        renderWith(scene, {"distributed (truth)", ShadowMethod::Distributed, truthRays}, 1);
    const Method methods[] = {
        {"hard", ShadowMethod::Hard},
        {"soft, RTSDF k·h/t", ShadowMethod::Soft, 0, false, false},
        {"soft, RTSDF + triangulation", ShadowMethod::Soft, 0, false, true},
        {"soft, centred + triangulation", ShadowMethod::Soft, 0, true, true},
        {"soft, centred + triangulation, no max step", ShadowMethod::Soft, 0, true, true, 0},
        {"soft, RTSDF + triangulation, no max step", ShadowMethod::Soft, 0, false, true, 0},
        {"shadow map, PCF 5x5", ShadowMethod::Pcf},
        {"shadow map, EVSM 15x15", ShadowMethod::Evsm},
        {"distributed, 16 rays", ShadowMethod::Distributed, 16},
        {"distributed, 64 rays", ShadowMethod::Distributed, 64},
    };
    // Pixels whose surface faces the light's centre (elsewhere every method says 0).
    std::vector<char> facing(truth.shadow.size(), 0);
    const Camera camera(scene.camera);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t i = size_t(y) * width + x;
            if (!std::isfinite(truth.depth[i])) continue;
            const Vec3 p = camera.pixelRay(x, y).at(truth.depth[i]);
            const Vec3 n(truth.normal[3 * i], truth.normal[3 * i + 1], truth.normal[3 * i + 2]);
            facing[i] = dot(n, towardLight(scene.lighting.lights[0], p).dir) > 0;
        }
    std::printf("%dx%d, %d threads, truth: distributed with %d rays per point (%.0f ms)\n\n", width,
                height, threads, truthRays, truth.ms);
    std::printf(
        "| method | ms (median of %d) | shadow evaluations per pixel | RMSE | max error | pixels "
        "compared |\n",
        reps);
    std::printf("| --- | --- | --- | --- | --- | --- |\n");
    for (const Method& m : methods) {
        const Run r = renderWith(scene, m, reps);
        double sq = 0, worst = 0;
        size_t n = 0;
        for (size_t i = 0; i < truth.shadow.size(); ++i) {
            if (!facing[i] || (truth.shadow[i] >= 0.99f && r.shadow[i] >= 0.99f)) continue;
            const double e = std::fabs(double(r.shadow[i]) - truth.shadow[i]);
            sq += e * e;
            worst = std::max(worst, e);
            ++n;
        }
        std::printf("| %s | %.1f | %.1f | %.4f | %.3f | %zu |\n", m.name, r.ms,
                    r.evaluationsPerPixel, n ? std::sqrt(sq / n) : 0.0, worst, n);
        std::fflush(stdout);
    }
    return 0;
}
