// Soft shadows of a deforming mesh, per frame, against a ground truth (issue 16; RTSDF §2.4-2.5):
// the skinned tube of data/meshes/animated/bending_tube.gltf bends on a floor under a sun 3
// degrees wide. Primary rays hit its triangles (primary_triangles, RTSDF's hybrid mode), so every
// method shades the same points and only the shadows differ:
//  - rtsdf x: the SDF regenerated every frame by RTSDF's pipeline (x rays per vertex, alpha 0.8),
//    SDF soft shadows (k h / t);
//  - rebake: the exact bake every frame at the same resolution, SDF soft shadows (the soft-shadow
//    estimate's own error, without RTSDF's);
//  - truth: the exact bake at twice the resolution, distributed shadow rays (--truth per point).
// Each SDF is also shaded with 16 distributed rays, which separates the soft-shadow estimate's own
// error from the SDF's.
// Per method: the shadow AOV's RMSE against the truth over the shadowed pixels (either below
// 0.99), its mean and worst over the frames, and the median frame time (bake + render).
//
//   build/release/bench/sdftrace_dynamic_shadow_bench [--frames 12 --resolution 96 --truth 256
//       --width 320 --height 200]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "bench_flags.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/animated_scene.h"
#include "sdftrace/scene/plan_render.h"

using namespace sdft;

namespace {

using Clock = std::chrono::steady_clock;

std::string sceneText(int width, int height, const std::string& tube, const std::string& render) {
    return R"({"camera": {"eye": [1.6, 2.2, 3.4], "target": [0.4, 0.5, 0], "fov": 40, "width": )" +
           std::to_string(width) + R"(, "height": )" + std::to_string(height) + R"(},
      "ambient": [0.1, 0.1, 0.1],
      "lights": [{"type": "directional", "direction": [-0.6, -1, -0.4], "angle": 3, "intensity": 2}],
      "objects": [
        {"type": "box", "size": [6, 0.2, 6], "translate": [0, -0.1, 0]},
        {"mesh": "bending_tube.gltf", "play": {"loop": false}, "band": 12, )" +
           tube + R"(}],
      "render": {"primary_triangles": true, )" +
           render + "}}";
}

struct Method {
    std::string name, tube, render;
};

// RMSE of a shadow AOV against the truth's over the shadowed pixels (either below 0.99).
double rmse(const std::vector<float>& shadow, const std::vector<float>& truth) {
    double sq = 0;
    size_t n = 0;
    for (size_t i = 0; i < shadow.size(); ++i) {
        if (shadow[i] >= 0.99f && truth[i] >= 0.99f) continue;
        sq += (double(shadow[i]) - truth[i]) * (double(shadow[i]) - truth[i]);
        ++n;
    }
    return n ? std::sqrt(sq / static_cast<double>(n)) : 0;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0 : v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
    int frames = 12, resolution = 96, truthRays = 256, width = 320, height = 200;
    constexpr const char* kUsage =
        "usage: sdftrace_dynamic_shadow_bench [--frames 12] [--resolution 96] [--truth 256]\n"
        "       [--width 320] [--height 200]\n";
    if (const int status = bench::checkFlagPairs(argc, argv, kUsage); status >= 0) return status;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string a = argv[i], v = argv[i + 1];
        if (a == "--frames")
            frames = bench::intFlag(a, v, 2);
        else if (a == "--resolution")
            resolution = bench::intFlag(a, v, 16);
        else if (a == "--truth")
            truthRays = bench::intFlag(a, v);
        else if (a == "--width")
            width = bench::intFlag(a, v, 16);
        else if (a == "--height")
            height = bench::intFlag(a, v, 16);
        else {
            std::fprintf(stderr, "unknown option %s\n", a.c_str());
            return 2;
        }
    }
    const std::string res = "\"resolution\": " + std::to_string(resolution);
    const std::string soft = R"("shadow_method": "soft")";
    const std::string rays16 = R"("shadow_method": "distributed", "shadow_rays": 16)";
    const std::string rtsdf1 = res + R"(, "dynamic": {"method": "rtsdf", "rays": 1, "alpha": 0.8})";
    const std::string rtsdf4 = res + R"(, "dynamic": {"method": "rtsdf", "rays": 4, "alpha": 0.8})";
    const std::string rtsdf4a0 = res + R"(, "dynamic": {"method": "rtsdf", "rays": 4, "alpha": 0})";
    const std::string rebake = res + R"(, "dynamic": {"method": "rebake"})";
    const std::vector<Method> methods = {
        {"rtsdf x = 1, soft (RTSDF k h / t)", rtsdf1, soft},
        {"rtsdf x = 4, soft (RTSDF k h / t)", rtsdf4, soft},
        {"rebake (exact), soft (RTSDF k h / t)", rebake, soft},
        {"rtsdf x = 4, distributed 16 rays", rtsdf4, rays16},
        {"rtsdf x = 4, alpha 0 (no history), distributed 16 rays", rtsdf4a0, rays16},
        {"rebake (exact), distributed 16 rays", rebake, rays16},
    };
    const Method truth{
        "truth",
        "\"resolution\": " + std::to_string(2 * resolution) +
            R"(, "dynamic": {"method": "rebake"})",
        R"("shadow_method": "distributed", "shadow_rays": )" + std::to_string(truthRays)};
    const std::string dir = std::string(SDFT_SOURCE_DIR) + "/data/meshes/animated";
    auto load = [&](const Method& m) {
        return AnimatedScene::fromText(sceneText(width, height, m.tube, m.render), m.name, dir);
    };
    // The frames of t in [0, 2): the clip's bend.
    auto shadowsOf = [&](const Method& m, std::vector<double>* times) {
        const AnimatedScene anim = load(m);
        AssetCache cache;
        std::vector<std::vector<float>> out;
        for (int k = 0; k < frames; ++k) {
            const auto t0 = Clock::now();
            const Scene s = anim.at(2.0 * k / frames, cache);
            const RenderPlan plan = planRender(s);
            Film film(plan.camera.width, plan.camera.height);
            render(plan, film);
            if (times) times->push_back(std::chrono::duration<double>(Clock::now() - t0).count());
            out.push_back(film.shadow);
        }
        return out;
    };
    const auto reference = shadowsOf(truth, nullptr);
    std::printf(
        "## Soft shadows of the bending tube per frame against the truth (%d frames, %dx%d, "
        "tube at %d cells, truth: %d cells and %d distributed rays)\n\n"
        "| method | RMSE, mean over frames | RMSE, worst frame | frame time (median) |\n"
        "| --- | --- | --- | --- |\n",
        frames, width, height, resolution, 2 * resolution, truthRays);
    for (const Method& m : methods) {
        std::vector<double> times;
        const auto shadows = shadowsOf(m, &times);
        double sumRmse = 0, worst = 0;
        for (int k = 0; k < frames; ++k) {
            const double e = rmse(shadows[k], reference[k]);
            sumRmse += e;
            worst = std::max(worst, e);
        }
        std::printf("| %s | %.4f | %.4f | %.1f ms |\n", m.name.c_str(), sumRmse / frames, worst,
                    1e3 * median(times));
        std::fflush(stdout);
    }
    return 0;
}
