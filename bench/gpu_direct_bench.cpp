// Direct lighting on the GPU against the CPU renderer on the same machine (issue 14, docs/gpu.md):
// whole frames as `sdftrace render --device cuda` and `--device cpu` render them (primary rays,
// normals, materials, each light's shadows, AO where asked), at 1280x720 (RTSDF's frame at
// 1920x1080). The GPU runs
// shadeDirectPixel one thread per pixel (gpu/gpu_render.h); the CPU the tile renderer on every
// hardware thread. Each case: a scene and a shadow method; evaluations per pixel count every
// field evaluation of the frame. Medians of --runs (GPU, after one untimed warm-up) and
// --cpu-runs.
//
//   sdftrace_gpu_direct_bench [--runs 10] [--cpu-runs 3] [--scenes all|city,rtsdf_frame,...]
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "gpu_bench_args.h"
#include "sdftrace/gpu/gpu_device.h"
#include "sdftrace/gpu/gpu_render.h"
#include "sdftrace/render/direct_pixel.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"

using namespace sdft;
using bench::median;

namespace {

struct Case {
    const char* scene;
    // hard, soft, distributed (4 rays), ao (hard shadows and AO), whitted (hard shadows; the
    // scene's gems made glass: Keinert et al. 2014's jewel with 2 reflection and 8 refraction
    // bounces and 3 discontinuity-reduction iterations), path (the path tracer, 1 spp, 10
    // bounces: Keinert's path-traced jewel), triangles (RTSDF's hybrid mode: primary rays on the
    // meshes' triangles, soft shadows in their SDFs)
    const char* shadows;
};

constexpr Case kCases[] = {{"city", "hard"},           {"city", "soft"},
                           {"demo", "hard"},           {"shadows", "soft"},
                           {"shadows", "distributed"}, {"many_blend", "ao"},
                           {"rock", "hard"},           {"jewel", "hard"},
                           {"jewel", "whitted"},       {"glass_shapes", "hard"},
                           {"jewel", "path"},          {"path", "path"},
                           {"textures", "soft"},       {"projected", "soft"},
                           {"hybrid", "triangles"},    {"rtsdf_frame", "triangles"}};

// RTSDF's frame (Tan et al. 2022, Table 1; issue 16's target): a moving mesh regenerated at size
// M (the teapot's fine grid 256 cells, x = 1), a floor, one sun, primary rays on the triangles and
// soft shadows marched in the SDF, at 1920x1080. This bench times its shading; the per-frame
// field (pose, coarse and fine passes) is gpu_bake_bench's "moving" rows.
constexpr const char* kRtsdfFrame = R"({
  "camera": {"eye": [0.2, 0.9, 2.2], "target": [0, 0.35, 0], "fov": 30, "width": 1920, "height": 1080},
  "lights": [{"type": "directional", "direction": [-0.4, -1, -0.5], "intensity": 2, "angle": 2}],
  "objects": [
    {"type": "box", "size": [4, 0.1, 4], "translate": [0, -0.05, 0]},
    {"mesh": "../data/meshes/teapot.obj", "resolution": 256, "scale": 0.15,
     "dynamic": {"method": "rtsdf", "rays": 1}}],
  "render": {"shadow_method": "soft", "primary_triangles": true}})";

// Keinert's jewel scene: its gems as absorbing dielectrics (diamond's and ruby's indices).
void makeGemsGlass(Scene& scene) {
    for (Material& m : scene.materials) {
        if (m.name == "gem" || m.name == "ruby") {
            m.kind = Material::Kind::Dielectric;
            m.ior = m.name == "gem" ? 2.42f : 1.77f;
            m.absorption = (Vec3(1.0f) - m.color) * 0.5f;
        }
    }
    scene.settings.maxReflections = 2;
    scene.settings.maxRefractions = 8;
    scene.settings.trace.discontinuityIters = 3;
}

}  // namespace

int main(int argc, char** argv) {
    bench::GpuBenchArgs args;
    if (!bench::parseGpuBenchArgs(argc, argv, "sdftrace_gpu_direct_bench", args, "all")) return 2;
    // --scenes a,b: only the cases of those scenes ("all": every case).
    auto wanted = [&](const char* scene) {
        return args.scenes == "all" ||
               ("," + args.scenes + ",").find("," + std::string(scene) + ",") != std::string::npos;
    };
    const int runs = args.runs, cpuRuns = args.cpuRuns;
    const GpuInfo& gpu = gpuInfo();
    std::printf(
        "| scene | shadows | evaluations per pixel (GPU / CPU) | GPU kernel ms | GPU frame ms | "
        "CPU ms | CPU / GPU kernel |\n| --- | --- | --- | --- | --- | --- | --- |\n");
    for (const Case& c : kCases) {
        if (!wanted(c.scene)) continue;
        try {
            const bool rtsdf = std::string(c.scene) == "rtsdf_frame";
            Scene scene = rtsdf ? parseSceneText(kRtsdfFrame, "rtsdf_frame",
                                                 std::string(SDFT_SOURCE_DIR) + "/examples")
                                : parseSceneFile(std::string(SDFT_SOURCE_DIR) + "/examples/" +
                                                 c.scene + ".json");
            const int W = rtsdf ? 1920 : 1280, H = rtsdf ? 1080 : 720;
            scene.camera.width = W;
            scene.camera.height = H;
            const std::string s = c.shadows;
            scene.settings.shadows = true;
            scene.settings.primaryTriangles = s == "triangles";
            scene.settings.shadowMethod = s == "soft" || s == "triangles" ? ShadowMethod::Soft
                                          : s == "distributed" ? ShadowMethod::Distributed
                                                               : ShadowMethod::Hard;
            scene.settings.shadowRays = 4;
            scene.settings.ambientOcclusion = s == "ao";
            if (s == "whitted") makeGemsGlass(scene);
            if (s == "path") {
                scene.settings.pathTracing = true;
                scene.settings.samplesPerPixel = 1;
                scene.settings.maxDepth = 10;
            }
            const RenderPlan plan = planRender(scene);
            if (const std::string why = directPixelUnsupported(plan); !why.empty()) {
                std::printf("| %s | %s | skipped: %s |\n", c.scene, c.shadows, why.c_str());
                continue;
            }
            const double pixels = static_cast<double>(W) * H;
            std::vector<double> cpuMs;
            double cpuEvals = 0;
            for (int r = 0; r < cpuRuns; ++r) {
                Film film(W, H, Film::bit(Aov::Color));
                const RenderStats st = render(plan, film, false);
                cpuMs.push_back(st.seconds * 1e3);
                cpuEvals = static_cast<double>(st.totalEvaluations()) / pixels;
            }
            const double cpu = median(cpuMs);
            if (!gpu.present) {
                std::printf("| %s | %s | - / %.2f | - | - | %.1f | - |\n", c.scene, c.shadows,
                            cpuEvals, cpu);
                continue;
            }
            const GpuDirectRenderer renderer(plan, "bench");
            FrameView frame;
            frame.camera = plan.camera;
            std::vector<double> kernel, whole;
            double gpuEvals = 0;
            for (int r = 0; r < runs + 1; ++r) {
                Film film(W, H, Film::bit(Aov::Color));
                const RenderStats st = renderer.render(frame, film);
                if (r == 0) {  // the first launch loads the module: not timed
                    gpuEvals = static_cast<double>(st.totalEvaluations()) / pixels;
                    continue;
                }
                kernel.push_back(st.gpuKernelMs);
                whole.push_back(st.gpuFrameMs);
            }
            const double k = median(kernel);
            std::printf("| %s | %s | %.2f / %.2f | %.3f | %.3f | %.1f | %.0fx |\n", c.scene,
                        c.shadows, gpuEvals, cpuEvals, k, median(whole), cpu, cpu / k);
        } catch (const std::exception& e) {
            std::printf("| %s | %s | error: %s |\n", c.scene, c.shadows, e.what());
        }
        std::fflush(stdout);
    }
    return 0;
}
