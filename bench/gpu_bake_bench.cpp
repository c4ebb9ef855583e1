// Mesh bakes on the GPU against the CPU on the same machine (issue 14, docs/gpu.md), at RTSDF's
// sizes (Tan et al. 2022, Tables 1 and 3): jump flooding of a voxelized mesh over N^3 vertices
// (N = 128, 256; RTSDF on an RTX 2080 Ti: 2.34 and 21.89 ms), and RTSDF's whole per-frame field at
// size M (coarse 128^3, fine 256^3) with x = 1, 5 and 10 rays per vertex and frame, accumulated
// (eq. 1): voxelization, jump flooding, signs, rays, each pass timed by CUDA events. Beside each,
// the CPU's run of the same bake on every hardware thread. Then a moving mesh's frames with the
// history kept on the device against copied to it and back. Medians of --runs (GPU, after one
// untimed warm-up) and --cpu-runs.
//
//   sdftrace_gpu_bake_bench [--runs 10] [--cpu-runs 3] [--scenes stanford-bunny,teapot]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "gpu_bench_args.h"
#include "sdftrace/bake/jump_flood.h"
#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/bake/surface_seeds.h"
#include "sdftrace/gpu/gpu_bake.h"
#include "sdftrace/gpu/gpu_complete_grid.h"
#include "sdftrace/io/mesh_io.h"

using namespace sdft;
using bench::median;

namespace {

// N^3 vertices over the mesh's bounds with a 4 % margin.
GridShape cubeOfVertices(const TriangleMesh& mesh, int n) {
    const Bounds3 b = mesh.bounds();
    const Vec3 e = b.extent();
    const float side = maxComponent(e) * 1.08f;
    GridShape s;
    for (int a = 0; a < 3; ++a) s.cells[a] = n - 1;
    s.voxelSize = side / static_cast<float>(n - 1);
    s.origin = b.center() - Vec3(side * 0.5f);
    return s;
}

double msSince(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

void jumpFloodRows(const std::string& name, const TriangleMesh& mesh, const GpuMeshBaker* gpu,
                   int runs, int cpuRuns) {
    for (int n : {128, 256}) {
        const GridShape s = cubeOfVertices(mesh, n);
        const SurfaceSeeds seeds = seedSurfaceVertices(mesh, s);
        std::vector<double> cpu;
        for (int r = 0; r < cpuRuns; ++r) {
            const auto t = std::chrono::steady_clock::now();
            jumpFlood(s, seeds.point, JfaVariant::Plain);
            cpu.push_back(msSince(t));
        }
        double gpuMs = 0, seedMs = 0;
        const size_t passes = jumpFloodOffsets(s, JfaVariant::Plain).size();
        if (gpu) {
            std::vector<double> jfa, seed;
            for (int r = 0; r <= runs; ++r) {
                GpuBakeTimes t;
                gpu->jumpFloodPoints(s, seeds.point, JfaVariant::Plain, &t);
                GpuBakeTimes all;
                gpu->jumpFlood(s, JfaVariant::Plain, SignMethod::BetaShell, 0.5f, &all);
                if (r == 0) continue;  // warm-up
                jfa.push_back(t.jfaMs);
                seed.push_back(all.seedMs);
            }
            gpuMs = median(jfa);
            seedMs = median(seed);
        }
        if (!gpu) {
            std::printf("| %s | jump flooding %d^3 (%zu passes) | - | - | %.1f | - |\n",
                        name.c_str(), n, passes, median(cpu));
            continue;
        }
        std::printf("| %s | jump flooding %d^3 (%zu passes) | %.3f | %.3f | %.1f | %.0f |\n",
                    name.c_str(), n, passes, gpuMs, seedMs, median(cpu), median(cpu) / gpuMs);
    }
}

void rtsdfRows(const std::string& name, const TriangleMesh& mesh, const GpuMeshBaker* gpu, int runs,
               int cpuRuns) {
    const GridShape fine = cubeOfVertices(mesh, 256);
    for (int x : {1, 5, 10}) {
        RtsdfOptions o;
        o.rays = x;
        double cpuMs = 0;
        if (x == 1 || cpuRuns > 1) {  // the CPU at x = 1 only, unless asked for more runs
            const MeshBvh bvh(mesh);
            RtsdfHistory h;
            o.history = &h;
            std::vector<double> cpu;
            for (int r = 0; r < cpuRuns; ++r) {
                const auto t = std::chrono::steady_clock::now();
                bakeRtsdfSamples(mesh, bvh, fine, o);
                cpu.push_back(msSince(t));
            }
            cpuMs = median(cpu);
        }
        if (!gpu) {
            std::printf("| %s | rtsdf M, x = %d | - | - | - | - | - | - | %s |\n", name.c_str(), x,
                        cpuMs > 0 ? std::to_string(cpuMs).substr(0, 7).c_str() : "-");
            continue;
        }
        RtsdfHistory h;
        o.history = &h;
        std::vector<double> seed, jfa, sign, ray, kernel, wall;
        size_t refined = 0;
        for (int r = 0; r <= runs; ++r) {
            GpuBakeTimes t;
            RtsdfStats st;
            gpu->rtsdf(fine, o, &st, &t);
            if (r == 0) continue;
            seed.push_back(t.seedMs);
            jfa.push_back(t.jfaMs);
            sign.push_back(t.signMs);
            ray.push_back(t.rayMs);
            kernel.push_back(t.kernelMs());
            wall.push_back(t.totalMs);
            refined = st.refined;
        }
        std::printf(
            "| %s | rtsdf M, x = %d (%zu vertices refined) | %.3f | %.3f | %.3f | %.3f | %.3f | "
            "%.2f | %s |\n",
            name.c_str(), x, refined, median(seed), median(jfa), median(sign), median(ray),
            median(kernel), median(wall),
            cpuMs > 0 ? std::to_string(cpuMs).substr(0, 7).c_str() : "-");
    }
}

// RTSDF §2.5's per-frame regeneration of a moving mesh (fig. 5's teapot on a circle, here each
// mesh, a tenth of a radian per frame around a circle of a quarter of its size) at size M, x = 1:
// per frame the mesh posed on the device (positions uploaded, LBVH rebuilt there, the winding tree
// on the host or over the LBVH on the device), the field accumulated with f_{t-1} and f_t kept on
// the device (accumulateOnDevice) and the frame's complete block grid refreshed there
// (GpuCompleteGrid), beside the same field with the history copied up and back and the field
// returned (rtsdf with a host history).
void movingRows(const std::string& name, const TriangleMesh& rest, bool present, int runs) {
    for (const GpuWinding winding : {GpuWinding::MedianTree, GpuWinding::Lbvh}) {
        const char* tree = winding == GpuWinding::Lbvh ? "LBVH dipoles (device)" : "median (host)";
        if (!present) {
            std::printf("| %s | moving, M, x = 1 | %s | - | - | - | - | - | - |\n", name.c_str(),
                        tree);
            continue;
        }
        GpuMeshBaker gpu(rest, winding);
        const Bounds3 b = rest.bounds();
        const float radius = 0.25f * maxComponent(b.extent());
        TriangleMesh span = rest;
        span.positions = {b.lo - Vec3(radius * 1.2f), b.hi + Vec3(radius * 1.2f)};
        const GridShape fine = cubeOfVertices(span, 256);
        // A complete grid's layout is its shape's alone: any samples make it.
        GpuCompleteGrid grid(
            Grid::completeFromDense(fine, std::vector<float>(fine.vertexCount(), 1.0f), 4, 1e6f));
        RtsdfOptions o;
        o.rays = 1;
        RtsdfHistory host;
        host.alpha = 0.95f;
        std::vector<double> pose, kernel, device, refresh, copied;
        for (int f = 0; f <= runs; ++f) {
            const float a = 0.1f * static_cast<float>(f);
            TriangleMesh mesh = rest;
            for (Vec3& p : mesh.positions) p += Vec3(radius * std::cos(a), 0, radius * std::sin(a));
            GpuBakeTimes t;
            gpu.pose(mesh, &t);
            const float* field =
                gpu.accumulateOnDevice(fine, o, host.alpha, f == 0 ? &host : nullptr, nullptr, &t);
            GpuRefreshTimes r;
            grid.refresh(field, &r);
            GpuBakeTimes c;
            o.history = &host;
            gpu.rtsdf(fine, o, nullptr, &c);
            o.history = nullptr;
            if (f == 0) continue;
            pose.push_back(t.poseMs);
            kernel.push_back(t.kernelMs());
            device.push_back(t.totalMs);
            refresh.push_back(r.totalMs);
            copied.push_back(c.totalMs);
        }
        std::printf("| %s | moving, M, x = 1 | %s | %.3f | %.3f | %.2f | %.2f | %.2f | %.2f |\n",
                    name.c_str(), tree, median(pose), median(kernel), median(device),
                    median(refresh), median(copied),
                    median(pose) + median(device) + median(refresh));
    }
}

}  // namespace

int main(int argc, char** argv) {
    bench::GpuBenchArgs args;
    if (!bench::parseGpuBenchArgs(argc, argv, "sdftrace_gpu_bake_bench", args,
                                  "stanford-bunny,teapot"))
        return 2;
    std::vector<std::string> names;
    std::stringstream list(args.scenes);
    for (std::string n; std::getline(list, n, ',');) names.push_back(n);
    const bool present = gpuInfo().present;
    std::printf("| mesh | triangles | LBVH build on the GPU, ms |\n| --- | --- | --- |\n");
    std::vector<TriangleMesh> meshes;
    std::vector<std::unique_ptr<GpuMeshBaker>> bakers;
    for (const std::string& n : names) {
        meshes.push_back(loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + n + ".obj"));
        bakers.push_back(present ? std::make_unique<GpuMeshBaker>(meshes.back()) : nullptr);
        std::printf(
            "| %s | %zu | %s |\n", n.c_str(), meshes.back().triangles.size(),
            present ? std::to_string(bakers.back()->lbvhBuildMs()).substr(0, 6).c_str() : "-");
    }
    std::printf(
        "\n| mesh | pass | GPU jfa ms | GPU seeds ms | CPU jfa ms | CPU / GPU |\n| --- | --- | "
        "--- | --- | --- | --- |\n");
    for (size_t i = 0; i < names.size(); ++i)
        jumpFloodRows(names[i], meshes[i], bakers[i].get(), args.runs, args.cpuRuns);
    std::printf(
        "\n| mesh | frame | GPU seeds ms | GPU jfa ms | GPU signs ms | GPU rays ms | GPU kernels "
        "ms | GPU call ms (copies) | CPU frame ms |\n| --- | --- | --- | --- | --- | --- | --- | "
        "--- | --- |\n");
    for (size_t i = 0; i < names.size(); ++i)
        rtsdfRows(names[i], meshes[i], bakers[i].get(), args.runs, args.cpuRuns);
    std::printf(
        "\n| mesh | frame | winding tree | pose ms (wall: upload, LBVH, winding tree) | GPU "
        "kernels ms | field on the device, call ms | grid refreshed on the device ms | field and "
        "history copied, call ms | pose + field + grid ms |\n| --- | --- | --- | --- | --- | --- "
        "| --- | --- | --- |\n");
    for (size_t i = 0; i < names.size(); ++i) movingRows(names[i], meshes[i], present, args.runs);
    return 0;
}
