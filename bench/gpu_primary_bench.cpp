// Primary rays on the GPU against the CPU on the same machine (issue 14, docs/gpu.md): Keinert et
// al. 2014's ray-cast timings (city 16.8 ms, jewel 2.98 ms at 1280x720 on a GTX Titan) and a
// level set of about 512 cells at 1024^2. Both devices run the same tracer: the GPU one thread per
// pixel (tracePrimaryPixel, gpu/gpu_primary.h), the CPU the renderer's packets of a 16x16 tile on
// every hardware thread. Primary rays and their normals, no shading; evaluations per ray count
// the march only. Medians of --runs.
// bunny512dda: that level set as a lone grid traced by Jamriška's two-level DDA, without and with
// §6's min/max buffer (128 pixels; the CPU's build and the GPU's, gpu/gpu_minmax.cuh, are timed
// beside the rays): both devices run tracePrimaryPixel per pixel; evaluations are trilinear
// reconstructions.
//
//   sdftrace_gpu_primary_bench [--runs 10] [--cpu-runs 3] [--scenes
//   city,jewel,bunny512,bunny512dda]
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "gpu_bench_args.h"
#include "sdftrace/core/error.h"
#include "sdftrace/gpu/gpu_device.h"
#include "sdftrace/gpu/gpu_primary.h"
#include "sdftrace/render/normal_stencil.h"
#include "sdftrace/render/render_plan.h"
#include "sdftrace/scene/grid_scene.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"
#include "sdftrace/trace/field_tracer.h"

using namespace sdft;
using bench::median;

namespace {

struct Case {
    std::string name;
    Scene scene;
};

Case loadCase(const std::string& name) {
    const std::string dir = std::string(SDFT_SOURCE_DIR) + "/examples/";
    if (name == "bunny512" || name == "bunny512dda") {
        // A sparse level set of the Stanford bunny, 512 cells along its longest axis, seen whole;
        // a band of 8 voxels, wider than a pixel's footprint here (docs/scene-format.md).
        const std::string text = R"({"camera": {"eye": [0, 1.0, 3.2], "target": [0, 0.45, 0],
            "fov": 30, "width": 1024, "height": 1024},
          "lights": [{"type": "directional", "direction": [-0.4, -1, -0.5]}],
          "objects": [{"mesh": "../data/meshes/stanford-bunny.obj", "resolution": 512,
                       "band": 8, "scale": 6, "translate": [0.1, -0.2, 0]}]})";
        static const Scene baked = parseSceneText(text, "bunny512", dir);  // baked once
        Scene scene = baked;
        if (name == "bunny512dda") {  // its grid alone, framed as `sdftrace render grid.sdfg`
            const RenderPlan plan = planRender(scene);
            SDFT_CHECK(plan.tape.grids().size() == 1);
            const std::shared_ptr<const Grid> g = plan.tape.grids()[0];
            scene = sceneForObject(node::grid(g), g->surfaceBounds());
            scene.camera.width = scene.camera.height = 1024;
        }
        return {name, std::move(scene)};
    }
    Case c{name, parseSceneFile(dir + name + ".json")};
    c.scene.camera.width = 1280;
    c.scene.camera.height = 720;
    return c;
}

using Clock = std::chrono::steady_clock;

// Milliseconds since `start`; the evaluations per ray of a w x h image from per-part counts.
double finish(Clock::time_point start, const std::vector<uint64_t>& evals, int w, int h,
              double& evaluationsPerRay) {
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    uint64_t total = 0;
    for (uint64_t e : evals) total += e;
    evaluationsPerRay = static_cast<double>(total) / (static_cast<double>(w) * h);
    return ms;
}

// The CPU renderer's primary rays: 16x16 tiles, one packet each, then the hits' normals in one
// batch of stencil points, on every hardware thread (what the GPU's threads do per pixel).
double cpuPrimaryMs(const RenderPlan& plan, const Camera& camera, const TraceOptions& options,
                    double& evaluationsPerRay) {
    const int w = plan.camera.width, h = plan.camera.height, tilesX = (w + 15) / 16,
              tilesY = (h + 15) / 16;
    std::vector<uint64_t> evals(static_cast<size_t>(tilesX) * tilesY);
    const auto start = std::chrono::steady_clock::now();
    tbb::parallel_for(0, tilesX * tilesY, [&](int tile) {
        thread_local PacketScratch scratch;
        thread_local std::vector<RaySegment> segments;
        thread_local std::vector<TraceResult> results;
        thread_local std::vector<float> sx, sy, sz, sf;
        const int x0 = (tile % tilesX) * 16, y0 = (tile / tilesX) * 16;
        const int x1 = std::min(w, x0 + 16), y1 = std::min(h, y0 + 16);
        segments.clear();
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x)
                segments.push_back({camera.pixelRay(x, y), 0.0f, plan.settings.maxDistance});
        results.resize(segments.size());
        tracePacket(plan.tape, segments, options, results, scratch);
        const NormalEstimator est = plan.settings.normals;
        const int sn = stencilSize(est);
        sx.clear();
        sy.clear();
        sz.clear();
        for (size_t i = 0; i < results.size(); ++i) {
            if (!results[i].hit) continue;
            const Vec3 p = segments[i].ray.at(results[i].t);
            const float eps = primaryNormalSpacing(results[i].t, options.pixelRadius,
                                                   plan.settings.normalSpacingMin);
            for (int k = 0; k < sn; ++k) {
                const Vec3 q = p + stencilOffset(est, k) * eps;
                sx.push_back(q.x);
                sy.push_back(q.y);
                sz.push_back(q.z);
            }
        }
        sf.resize(sx.size());
        plan.tape.evalBatch(sx.data(), sy.data(), sz.data(), sf.data(), static_cast<int>(sx.size()),
                            scratch.batch);
        uint64_t e = 0;
        for (const TraceResult& r : results) e += r.evaluations;
        evals[static_cast<size_t>(tile)] = e;
    });
    return finish(start, evals, w, h, evaluationsPerRay);
}

// The DDA's primary rays per pixel on every hardware thread, the min/max buffer (when `resolution`
// > 0) built first and timed with them.
double cpuDdaMs(const RenderPlan& plan, PrimaryPixelView view, int resolution,
                double& evaluationsPerRay, double& buildMs) {
    const int w = plan.camera.width, h = plan.camera.height;
    std::vector<uint64_t> evals(static_cast<size_t>(h));
    const auto start = std::chrono::steady_clock::now();
    const MinMaxBuffer buffer =
        resolution > 0 ? MinMaxBuffer::build(plan.ddaGrid->view(), view.camera, resolution)
                       : MinMaxBuffer{};
    buildMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    view.minMax = buffer.view();
    tbb::parallel_for(0, h, [&](int y) {
        uint64_t e = 0;
        for (int x = 0; x < w; ++x) e += tracePrimaryPixel(view, x, y).trace.evaluations;
        evals[static_cast<size_t>(y)] = e;
    });
    return finish(start, evals, w, h, evaluationsPerRay);
}

// The DDA rows of a lone grid: without and with the min/max buffer.
void ddaRows(const std::string& name, const RenderPlan& plan, const PrimaryPixelView& view,
             int runs, int cpuRuns) {
    const int w = plan.camera.width, h = plan.camera.height;
    const double pixels = static_cast<double>(w) * h;
    std::unique_ptr<GpuTape> tape;
    if (gpuInfo().present) tape = std::make_unique<GpuTape>(plan.tape);
    for (int resolution : {0, 128}) {
        double cpuEvals = 0, cpuBuild = 0;
        std::vector<double> cpuMs;
        for (int r = 0; r < cpuRuns; ++r)
            cpuMs.push_back(cpuDdaMs(plan, view, resolution, cpuEvals, cpuBuild));
        const double cpu = median(cpuMs);
        const std::string label =
            name + (resolution > 0 ? " (min/max " + std::to_string(resolution) + ")" : " (DDA)");
        if (!tape) {
            std::printf("| %s | %dx%d | - / %.2f | - | - | - | %.2f (buffer %.2f) | - |\n",
                        label.c_str(), w, h, cpuEvals, cpu, cpuBuild);
            continue;
        }
        PrimaryPixelView v = view;
        MinMaxBuffer buffer;
        if (resolution > 0) {
            buffer = MinMaxBuffer::build(plan.ddaGrid->view(), v.camera, resolution);
            v.minMax = buffer.view();
        }
        std::vector<double> kernel, whole, build;
        double gpuEvals = 0;
        for (int r = 0; r < runs + 1; ++r) {
            const GpuPrimaryImage img = tracePrimaryGpu(*tape, v, w, h);
            const double b = resolution > 0 ? buildMinMaxGpu(*tape, v.ddaGrid, plan.ddaGrid->view(),
                                                             v.camera, resolution)
                                                  .ms
                                            : 0.0;
            if (r == 0) {
                double e = 0;
                for (int32_t x : img.evaluations) e += x;
                gpuEvals = e / pixels;
                continue;
            }
            kernel.push_back(img.kernelMs + b);
            whole.push_back(img.frameMs);
            build.push_back(b);
        }
        const double k = median(kernel);
        std::printf(
            "| %s | %dx%d | %.2f / %.2f | %.3f (buffer %.3f) | %.3f | %.2f | %.2f (buffer "
            "%.2f) | %.1fx |\n",
            label.c_str(), w, h, gpuEvals, cpuEvals, k, median(build), median(whole),
            pixels / (k * 1e6), cpu, cpuBuild, cpu / k);
        std::fflush(stdout);
    }
}

}  // namespace

int main(int argc, char** argv) {
    bench::GpuBenchArgs args;
    if (!bench::parseGpuBenchArgs(argc, argv, "sdftrace_gpu_primary_bench", args,
                                  "city,jewel,bunny512,bunny512dda"))
        return 2;
    const int runs = args.runs, cpuRuns = args.cpuRuns;
    const GpuInfo& gpu = gpuInfo();
    const std::string scenes = args.scenes;
    std::printf(
        "| scene | pixels | evaluations per ray (GPU / CPU) | GPU kernel ms | GPU frame ms "
        "| G rays/s | CPU ms | GPU / CPU |\n| --- | --- | --- | --- | --- | --- | --- | "
        "--- |\n");
    std::stringstream list(scenes);
    for (std::string name; std::getline(list, name, ',');) {
        try {
            const Case c = loadCase(name);
            const RenderPlan plan = planRender(c.scene);
            if (plan.meshPrimary) {  // triangles: GpuDirectRenderer uploads them
                std::printf("| %s | skipped: triangle primaries |\n", name.c_str());
                continue;
            }
            FrameView frame;
            frame.camera = plan.camera;
            const PrimaryPixelView view = primaryPixelView(plan, frame);
            if (plan.ddaGrid) {
                ddaRows(name, plan, view, runs, cpuRuns);
                continue;
            }
            const int w = plan.camera.width, h = plan.camera.height;
            const double pixels = static_cast<double>(w) * h;
            double cpuEvals = 0;
            std::vector<double> cpuMs;
            for (int r = 0; r < cpuRuns; ++r)
                cpuMs.push_back(cpuPrimaryMs(plan, view.camera, view.options, cpuEvals));
            const double cpu = median(cpuMs);
            if (!gpu.present) {
                std::printf("| %s | %dx%d | - / %.2f | - | - | - | %.2f | - |\n", name.c_str(), w,
                            h, cpuEvals, cpu);
                continue;
            }
            const GpuTape tape(plan.tape);
            std::vector<double> kernel, whole;
            double gpuEvals = 0;
            for (int r = 0; r < runs + 1; ++r) {
                const GpuPrimaryImage img = tracePrimaryGpu(tape, view, w, h);
                if (r == 0) {  // the first launch loads the module: not timed
                    double e = 0;
                    for (int32_t v : img.evaluations) e += v;
                    gpuEvals = e / pixels;
                    continue;
                }
                kernel.push_back(img.kernelMs);
                whole.push_back(img.frameMs);
            }
            const double k = median(kernel);
            std::printf("| %s | %dx%d | %.2f / %.2f | %.3f | %.3f | %.2f | %.2f | %.1fx |\n",
                        name.c_str(), w, h, gpuEvals, cpuEvals, k, median(whole),
                        pixels / (k * 1e6), cpu, cpu / k);
        } catch (const std::exception& e) {
            std::printf("| %s | error: %s |\n", name.c_str(), e.what());
        }
        std::fflush(stdout);
    }
    return 0;
}
