// The GPU bakes against the CPU's (issue 14): the device-built LBVH's hits against the CPU-built
// one's, seeds, jump flooding, the signed jfa field and RTSDF's single and accumulated fine
// fields, each held to the CPU's run of the same header functions within float rounding (nvcc
// contracts multiply-adds into FMAs, so not bit for bit). The GPU cases skip without a GPU; what
// the GPU does not bake is one clear error everywhere.
#include "sdftrace/gpu/gpu_bake.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "sdftrace/bake/jump_flood.h"
#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/bake/seed_signs.h"
#include "sdftrace/bake/surface_seeds.h"
#include "sdftrace/core/error.h"
#include "sdftrace/gpu/gpu_device.h"
#include "sdftrace/io/mesh_io.h"

namespace sdft {
namespace {

TriangleMesh load(const std::string& name) {
    return loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + name);
}

GridShape shapeFor(const TriangleMesh& mesh, int resolution) {
    SampleOptions so;
    so.resolution = resolution;
    so.kind = GridKind::Dense;
    return gridShapeFor(mesh.bounds(), so);
}

// Meshes of different kinds: closed (bunny_npm), open with holes (elephant), thin parts (teapot).
const char* const kMeshes[] = {"bunny_npm.obj", "elephant-with-holes.obj", "teapot.obj"};

#define SKIP_WITHOUT_GPU() \
    if (!gpuInfo().present) GTEST_SKIP() << "no GPU: " << gpuInfo().why

TEST(GpuBake, WhatTheGpuDoesNotBakeIsOneClearError) {
    MeshBakeOptions o;
    o.method = MeshBakeMethod::Exact;
    EXPECT_EQ(gpuBakeUnsupported(o),
              "--method exact runs on the CPU only (the GPU bakes jfa and rtsdf)");
    o.method = MeshBakeMethod::Rtsdf;
    EXPECT_EQ(gpuBakeUnsupported(o), "");
    o.sign = SignMethod::RayParity;
    EXPECT_EQ(gpuBakeUnsupported(o),
              "--sign parity runs on the CPU only (the GPU signs by winding)");
    o.method = MeshBakeMethod::JumpFlood;
    o.sign = SignMethod::BetaShell;
    EXPECT_EQ(gpuBakeUnsupported(o), "");
    o.method = MeshBakeMethod::Danielsson;
    EXPECT_THROW(bakeMeshGpu(load("suzanne.obj"), o), InputError);
    if (gpuInfo().present) return;
    o.method = MeshBakeMethod::JumpFlood;
    try {
        bakeMeshGpu(load("suzanne.obj"), o);
        FAIL() << "bakeMeshGpu did not throw without a GPU";
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.rfind("GPU bake: ", 0), 0u) << m;
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    }
}

TEST(GpuBake, LbvhHitsMatchTheCpuBuiltTree) {
    SKIP_WITHOUT_GPU();
    for (const char* name : kMeshes) {
        SCOPED_TRACE(name);
        const TriangleMesh mesh = load(name);
        const GpuMeshBaker baker(mesh);
        const Lbvh cpu(mesh);
        const Bounds3 b = mesh.bounds();
        std::mt19937 rng(5);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        std::vector<Ray> rays;
        for (int i = 0; i < 20000; ++i) {
            const float z = 1 - 2 * u(rng), phi = 6.2831853f * u(rng);
            const float s = std::sqrt(std::fmax(0.0f, 1 - z * z));
            rays.push_back({b.lo + Vec3(u(rng), u(rng), u(rng)) * b.extent(),
                            Vec3(s * std::cos(phi), s * std::sin(phi), z)});
        }
        const float tnear = -1e-4f * length(b.extent());
        const std::vector<LbvhHit> gpu = baker.firstHits(rays, tnear);
        ASSERT_EQ(gpu.size(), rays.size());
        int differ = 0, hits = 0;
        for (size_t i = 0; i < rays.size(); ++i) {
            const LbvhHit c = lbvhFirstHit(cpu.view(), rays[i], tnear);
            hits += c.t != kInfinity;
            const bool same =
                (c.t == kInfinity) == (gpu[i].t == kInfinity) &&
                (c.t == kInfinity || (std::fabs(c.t - gpu[i].t) <= 1e-5f * std::fmax(1.0f, c.t) &&
                                      c.front == gpu[i].front));
            differ += !same;
        }
        EXPECT_GT(hits, 5000);
        EXPECT_LE(differ, 20) << differ << " of " << rays.size() << " rays differ";
        std::printf("[ gpu bake ] %s: LBVH of %zu triangles built in %.3f ms on the GPU\n", name,
                    mesh.triangles.size(), baker.lbvhBuildMs());
    }
}

TEST(GpuBake, SeedsAndJumpFloodingMatchTheCpu) {
    SKIP_WITHOUT_GPU();
    for (const char* name : kMeshes) {
        SCOPED_TRACE(name);
        const TriangleMesh mesh = load(name);
        const GpuMeshBaker baker(mesh);
        const GridShape s = shapeFor(mesh, 72);  // not a power of two, not cubic
        const SurfaceSeeds cpuSeeds = seedSurfaceVertices(mesh, s);
        const SurfaceSeeds gpuSeeds = baker.seeds(s);
        ASSERT_EQ(gpuSeeds.point.size(), cpuSeeds.point.size());
        size_t seeds = 0, differ = 0;
        for (size_t i = 0; i < cpuSeeds.point.size(); ++i) {
            const bool a = cpuSeeds.point[i].x != kNoSeed, b = gpuSeeds.point[i].x != kNoSeed;
            seeds += a;
            // Only a vertex at the reach's very edge may differ (its distance rounded apart).
            differ += a != b ||
                      (a && length(cpuSeeds.point[i] - gpuSeeds.point[i]) > 1e-4f * s.voxelSize);
        }
        EXPECT_GT(seeds, 1000u);
        EXPECT_LE(differ, seeds / 10000 + 2) << differ << " of " << seeds << " seeds differ";
        // Flooding the CPU's seeds: the same distances (a tie may pick another point as near).
        for (JfaVariant variant :
             {JfaVariant::Plain, JfaVariant::OnePlusJfa, JfaVariant::JfaPlusTwo}) {
            const std::vector<Vec3> cpu = jumpFlood(s, cpuSeeds.point, variant);
            GpuBakeTimes times;
            const std::vector<Vec3> gpu = baker.jumpFloodPoints(s, cpuSeeds.point, variant, &times);
            EXPECT_EQ(times.passMs.size(), jumpFloodOffsets(s, variant).size());
            const std::vector<float> dc = distancesToPoints(s, cpu), dg = distancesToPoints(s, gpu);
            size_t far = 0;
            for (size_t i = 0; i < dc.size(); ++i)
                far += std::fabs(dc[i] - dg[i]) > 1e-4f * s.voxelSize;
            EXPECT_LE(far, dc.size() / 10000) << far << " vertices differ";
        }
    }
}

// The whole jfa bake (seeds, flooding, winding-number signs) against the CPU's pipeline.
TEST(GpuBake, JfaFieldMatchesTheCpu) {
    SKIP_WITHOUT_GPU();
    for (const char* name : kMeshes) {
        SCOPED_TRACE(name);
        const TriangleMesh mesh = load(name);
        const GpuMeshBaker baker(mesh);
        const GridShape s = shapeFor(mesh, 64);
        const SurfaceSeeds seeds = seedSurfaceVertices(mesh, s);
        std::vector<float> cpu = distancesToPoints(s, jumpFlood(s, seeds.point, JfaVariant::Plain));
        signDistances(cpu, mesh, nullptr, s, seeds, SignMethod::WindingNumber);
        const std::vector<float> gpu =
            baker.jumpFlood(s, JfaVariant::Plain, SignMethod::WindingNumber, 0.5f);
        ASSERT_EQ(gpu.size(), cpu.size());
        size_t differ = 0;
        for (size_t i = 0; i < cpu.size(); ++i)
            differ += std::fabs(cpu[i] - gpu[i]) > 1e-4f * s.voxelSize;
        EXPECT_LE(differ, cpu.size() / 5000) << differ << " of " << cpu.size() << " differ";
    }
}

// RTSDF's fine field on the GPU against the CPU bake with its rays through the same LBVH code:
// the same coarse field, ray streams, votes and relaxation.
TEST(GpuBake, RtsdfMatchesTheCpuThroughTheSameLbvh) {
    SKIP_WITHOUT_GPU();
    for (const char* name : kMeshes) {
        SCOPED_TRACE(name);
        const TriangleMesh mesh = load(name);
        const GpuMeshBaker baker(mesh);
        const MeshBvh bvh(mesh);
        const GridShape s = shapeFor(mesh, 96);
        RtsdfOptions o;
        o.rays = 16;
        o.caster = RtsdfCaster::Lbvh;
        RtsdfStats cs, gs;
        const std::vector<float> cpu = bakeRtsdfSamples(mesh, bvh, s, o, 0, &cs);
        GpuBakeTimes times;
        const std::vector<float> gpu = baker.rtsdf(s, o, &gs, &times);
        ASSERT_EQ(gpu.size(), cpu.size());
        EXPECT_NEAR(double(gs.refined), double(cs.refined), 1e-3 * double(cs.refined) + 2);
        size_t differ = 0;
        for (size_t i = 0; i < cpu.size(); ++i)
            differ += std::fabs(cpu[i] - gpu[i]) > 1e-3f * s.voxelSize;
        EXPECT_LE(differ, cpu.size() / 2000) << differ << " of " << cpu.size() << " differ";
        EXPECT_GT(times.rayMs, 0.0);
        std::printf(
            "[ gpu bake ] %s at 96: %zu refined; GPU seeds %.2f ms, jfa %.2f ms, signs %.2f "
            "ms, rays %.2f ms, relax %.2f ms\n",
            name, gs.refined, times.seedMs, times.jfaMs, times.signMs, times.rayMs, times.relaxMs);
    }
}

// Eq. 1 over frames: the GPU's history evolves as the CPU's.
TEST(GpuBake, RtsdfAccumulatesLikeTheCpu) {
    SKIP_WITHOUT_GPU();
    const TriangleMesh mesh = load("bunny_npm.obj");
    const GpuMeshBaker baker(mesh);
    const MeshBvh bvh(mesh);
    const GridShape s = shapeFor(mesh, 64);
    RtsdfHistory cpuHistory, gpuHistory;
    RtsdfOptions o;
    o.rays = 2;
    o.caster = RtsdfCaster::Lbvh;
    for (int frame = 0; frame < 4; ++frame) {
        SCOPED_TRACE(frame);
        o.history = &cpuHistory;
        const std::vector<float> cpu = bakeRtsdfSamples(mesh, bvh, s, o);
        o.history = &gpuHistory;
        const std::vector<float> gpu = baker.rtsdf(s, o);
        EXPECT_EQ(gpuHistory.frames, cpuHistory.frames);
        size_t differ = 0;
        for (size_t i = 0; i < cpu.size(); ++i)
            differ += std::fabs(cpu[i] - gpu[i]) > 1e-3f * s.voxelSize;
        EXPECT_LE(differ, cpu.size() / 2000) << differ << " of " << cpu.size() << " differ";
    }
}

}  // namespace
}  // namespace sdft
