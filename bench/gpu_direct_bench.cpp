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
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "gpu_bench_args.h"
#include "sdftrace/gpu/gpu_bake.h"
#include "sdftrace/gpu/gpu_complete_grid.h"
#include "sdftrace/gpu/gpu_device.h"
#include "sdftrace/gpu/gpu_render.h"
#include "sdftrace/io/mesh_io.h"
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

// RTSDF's whole frame on the device (issue 16's target: <= 2 ms on the H200): per frame the
// teapot posed (a wobble about its vertical axis and a bob, inside the grid's margin), its field
// accumulated on the device (GpuMeshBaker::accumulateOnDevice), the plan's complete block grid
// refreshed there (GpuCompleteGrid, bound into the renderer's tapes) and the frame shaded: nothing
// of the field crosses to the host. The primary rays hit the posed triangles: the baker's LBVH,
// which the pose rebuilds (the pose's time), and its vertex normals (GpuMeshBaker::surface),
// which the renderer follows. Medians over `runs` frames after one untimed.
void rtsdfWholeFrame(const RenderPlan& plan, int runs) {
    const Grid* complete = nullptr;
    for (const auto& g : plan.tape.grids())
        if (g->isComplete()) complete = g.get();
    if (!complete) {
        std::printf("\nRTSDF whole frame: the plan has no complete grid\n");
        return;
    }
    const TriangleMesh rest = loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/teapot.obj");
    const auto state = std::make_shared<RtsdfDeviceState>(
        RtsdfDeviceState{GpuMeshBaker(rest, GpuWinding::Lbvh), std::nullopt});
    GpuMeshBaker& baker = state->baker;
    GpuCompleteGrid grid(*complete);
    GpuDirectRenderer renderer(plan, "bench", {{complete, grid.view()}});
    renderer.followMesh(0, state);  // the primary rays' triangles: each pose's
    RtsdfOptions o;
    o.rays = 1;
    const Vec3 c = rest.bounds().center();
    const float bob = 0.05f * maxComponent(rest.bounds().extent());
    FrameView frame;
    frame.camera = plan.camera;
    std::vector<double> pose, field, refresh, kernel, shade, whole;
    double moved = 0;
    for (int f = 0; f <= runs; ++f) {
        const float a = 0.15f * std::sin(0.3f * static_cast<float>(f));
        const float ca = std::cos(a), sa = std::sin(a);
        TriangleMesh mesh = rest;
        for (Vec3& p : mesh.positions) {
            const Vec3 q = p - c;
            p = c + Vec3(ca * q.x + sa * q.z, q.y + bob * std::sin(0.5f * f), -sa * q.x + ca * q.z);
        }
        const auto start = std::chrono::steady_clock::now();
        GpuBakeTimes t;
        baker.pose(mesh, &t);
        const float* f_t =
            baker.accumulateOnDevice(complete->shape(), o, 0.95f, nullptr, nullptr, &t);
        GpuRefreshTimes r;
        grid.refresh(f_t, &r);
        renderer.rebind({complete, grid.view()});
        Film film(plan.camera.width, plan.camera.height, Film::bit(Aov::Color));
        const RenderStats st = renderer.render(frame, film);
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        if (f == 0) continue;
        pose.push_back(t.poseMs);
        field.push_back(t.totalMs);
        refresh.push_back(r.totalMs);
        kernel.push_back(t.kernelMs() + r.blocksMs + r.skipMs + st.gpuKernelMs);
        shade.push_back(st.gpuFrameMs);
        whole.push_back(ms);
        moved = static_cast<double>(st.gpuBytesMoved) / 1e6;
    }
    std::printf(
        "\nRTSDF whole frame on the device (teapot M, x = 1, %dx%d, soft shadows, triangle "
        "primaries):\n\n| pose ms | field ms | grid refresh ms | shading ms (frame, film copied "
        "back) | GPU kernels ms | MB moved | whole frame ms (wall) |\n| --- | --- | --- | --- | "
        "--- | --- | --- |\n| %.3f | %.3f | %.3f | %.3f | %.3f | %.2f | %.3f |\n",
        plan.camera.width, plan.camera.height, median(pose), median(field), median(refresh),
        median(shade), median(kernel), moved, median(whole));
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
        "MB moved per frame | CPU ms | CPU / GPU kernel |\n| --- | --- | --- | --- | --- | --- | "
        "--- | --- |\n");
    std::vector<std::unique_ptr<RenderPlan>> wholeFrames;  // RTSDF's, timed after the table
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
                std::printf("| %s | %s | - / %.2f | - | - | - | %.1f | - |\n", c.scene, c.shadows,
                            cpuEvals, cpu);
                continue;
            }
            const GpuDirectRenderer renderer(plan, "bench");
            FrameView frame;
            frame.camera = plan.camera;
            std::vector<double> kernel, whole;
            double gpuEvals = 0, moved = 0;
            for (int r = 0; r < runs + 1; ++r) {
                Film film(W, H, Film::bit(Aov::Color));
                const RenderStats st = renderer.render(frame, film);
                if (r == 0) {  // the first launch loads the module: not timed
                    gpuEvals = static_cast<double>(st.totalEvaluations()) / pixels;
                    continue;
                }
                kernel.push_back(st.gpuKernelMs);
                whole.push_back(st.gpuFrameMs);
                moved = static_cast<double>(st.gpuBytesMoved) / 1e6;
            }
            const double k = median(kernel);
            std::printf("| %s | %s | %.2f / %.2f | %.3f | %.3f | %.2f | %.1f | %.0fx |\n", c.scene,
                        c.shadows, gpuEvals, cpuEvals, k, median(whole), moved, cpu, cpu / k);
            if (rtsdf) wholeFrames.push_back(std::make_unique<RenderPlan>(planRender(scene)));
        } catch (const std::exception& e) {
            std::printf("| %s | %s | error: %s |\n", c.scene, c.shadows, e.what());
        }
        std::fflush(stdout);
    }
    for (const auto& plan : wholeFrames) {
        try {
            rtsdfWholeFrame(*plan, runs);
        } catch (const std::exception& e) {
            std::printf("\nRTSDF whole frame: error: %s\n", e.what());
        }
    }
    return 0;
}
