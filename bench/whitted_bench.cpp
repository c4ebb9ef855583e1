// Keinert et al. 2014 §3.5 on a glass scene (issue 5): refracted rays inside convex objects jump
// to the object's bounding box and sphere trace back, against marching through the interior, in
// one run. examples/glass_shapes.json: a sphere, a rotated box, a dodecahedron, a rounded box, a
// sphere-box intersection and a capsule of absorbing glass over a floor.
//
// Per variant: render time (median of --reps), field evaluations of secondary rays per pixel and
// in all per pixel, and the largest colour difference between the two images.
//
//   build/release/bench/sdftrace_whitted_bench [--reps 7 --threads 2]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "bench_flags.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"

using namespace sdft;

int main(int argc, char** argv) {
    int reps = 7, threads = 2;
    constexpr const char* kUsage = "usage: sdftrace_whitted_bench [--reps 7] [--threads 2]\n";
    if (const int status = bench::checkFlagPairs(argc, argv, kUsage); status >= 0) return status;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string k = argv[i];
        if (k == "--reps") {
            reps = bench::intFlag(k, argv[i + 1]);
        } else if (k == "--threads") {
            threads = bench::intFlag(k, argv[i + 1]);
        } else {
            std::fprintf(stderr, "unknown option %s\n", k.c_str());
            return 2;
        }
    }
    Scene scene = parseSceneFile(std::string(SDFT_SOURCE_DIR) + "/examples/glass_shapes.json");
    scene.settings.threads = threads;
    std::vector<float> images[2];
    std::printf("%dx%d, %d threads\n\n", scene.camera.width, scene.camera.height, threads);
    std::printf(
        "| rays inside convex glass | ms (median of %d) | secondary evaluations per pixel | "
        "evaluations per pixel | secondary rays per pixel |\n| --- | --- | --- | --- | --- |\n",
        reps);
    for (int v = 0; v < 2; ++v) {
        scene.settings.convexBounds = v == 1;
        std::vector<double> ms;
        RenderStats st;
        const RenderPlan plan = planRender(scene);
        for (int r = 0; r < reps; ++r) {
            Film film(scene.camera.width, scene.camera.height);
            const auto t0 = std::chrono::steady_clock::now();
            st = render(plan, film);
            ms.push_back(
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                    .count());
            images[v] = film.color;
        }
        std::sort(ms.begin(), ms.end());
        const double px = double(scene.camera.width) * scene.camera.height;
        std::printf("| %s | %.1f | %.2f | %.2f | %.2f |\n",
                    v ? "bound, then back (Keinert §3.5)" : "march through the interior",
                    ms[ms.size() / 2], st.secondaryEvaluations / px, st.totalEvaluations() / px,
                    st.secondaryRays / px);
    }
    float worst = 0;
    size_t over = 0;
    for (size_t i = 0; i < images[0].size(); ++i) {
        const float d = std::fabs(images[0][i] - images[1][i]);
        worst = std::max(worst, d);
        over += d > 1e-3f;
    }
    std::printf("\nlargest colour difference %.4f; %zu of %zu channels differ by more than 1e-3\n",
                worst, over, images[0].size());
    return 0;
}
