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
#include "sdftrace/bake/winding_lbvh.h"
#include "sdftrace/bake/winding_number.h"
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

// Entries of two fields of one grid further apart than `tolerance`.
size_t differing(const std::vector<float>& a, const std::vector<float>& b, float tolerance) {
    size_t n = 0;
    for (size_t i = 0; i < a.size(); ++i) n += std::fabs(a[i] - b[i]) > tolerance;
    return n;
}

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

// The dipole tree built over the device's LBVH (winding_lbvh.h): the mesh's moments at the root,
// one triangle per leaf, and on the CPU its winding numbers within the dipoles' bound of the
// exact sum and its signs the median-split tree's (as LbvhWinding's on the CPU).
TEST(GpuBake, WindingTreeOverTheLbvhMatchesTheMedianTree) {
    SKIP_WITHOUT_GPU();
    for (const char* name : kMeshes) {
        SCOPED_TRACE(name);
        const TriangleMesh mesh = load(name);
        const GpuMeshBaker baker(mesh, GpuWinding::Lbvh);
        const std::vector<WindingNode> nodes = baker.windingNodes();
        const std::vector<float> corners = baker.windingCorners();
        ASSERT_EQ(nodes.size(), 2 * mesh.triangles.size() - 1);
        ASSERT_EQ(corners.size(), 9 * mesh.triangles.size());
        const LbvhWinding cpu(Lbvh(mesh).view());
        const WindingNode &root = nodes[0], &cpuRoot = cpu.nodes()[0];
        EXPECT_EQ(root.count, static_cast<int>(mesh.triangles.size()));
        EXPECT_NEAR(root.area, cpuRoot.area, 1e-9 * cpuRoot.area);
        EXPECT_NEAR(root.nx, cpuRoot.nx, 1e-9 * cpuRoot.area);
        EXPECT_NEAR(root.ny, cpuRoot.ny, 1e-9 * cpuRoot.area);
        EXPECT_NEAR(root.nz, cpuRoot.nz, 1e-9 * cpuRoot.area);
        for (size_t j = mesh.triangles.size() - 1; j < nodes.size(); ++j)
            ASSERT_EQ(nodes[j].count, 1);
        const WindingView gpu{nodes.data(), static_cast<int>(nodes.size()), corners.data()};
        const WindingNumber median(mesh);
        const Bounds3 b = mesh.bounds().expanded(0.1f * maxComponent(mesh.bounds().extent()));
        const int n = 20;
        int differ = 0;
        double worst = 0;
        for (int k = 0; k <= n; ++k)
            for (int j = 0; j <= n; ++j)
                for (int i = 0; i <= n; ++i) {
                    const Vec3 p = b.lo + b.extent() * Vec3(i, j, k) / static_cast<float>(n);
                    differ += windingInside(gpu, p, median.beta()) != median.inside(p);
                    if ((i + j + k) % 7 == 0)
                        worst = std::fmax(
                            worst,
                            std::fabs(windingNumberFast(gpu, p, median.beta()) - median.exact(p)));
                }
        EXPECT_LT(worst, 0.03);
        EXPECT_LE(differ, (n + 1) * (n + 1) * (n + 1) / 2000) << differ << " signs differ";
    }
}

// The whole jfa bake (seeds, flooding, winding-number signs) against the CPU's pipeline, with
// either winding tree on the device.
TEST(GpuBake, JfaFieldMatchesTheCpu) {
    SKIP_WITHOUT_GPU();
    for (const char* name : kMeshes)
        for (const GpuWinding winding : {GpuWinding::MedianTree, GpuWinding::Lbvh}) {
            SCOPED_TRACE(name);
            SCOPED_TRACE(winding == GpuWinding::Lbvh ? "lbvh dipoles" : "median tree");
            const TriangleMesh mesh = load(name);
            const GpuMeshBaker baker(mesh, winding);
            const GridShape s = shapeFor(mesh, 64);
            const SurfaceSeeds seeds = seedSurfaceVertices(mesh, s);
            std::vector<float> cpu =
                distancesToPoints(s, jumpFlood(s, seeds.point, JfaVariant::Plain));
            signDistances(cpu, mesh, nullptr, s, seeds, SignMethod::WindingNumber);
            const std::vector<float> gpu =
                baker.jumpFlood(s, JfaVariant::Plain, SignMethod::WindingNumber, 0.5f);
            ASSERT_EQ(gpu.size(), cpu.size());
            const size_t differ = differing(cpu, gpu, 1e-4f * s.voxelSize);
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
        const size_t differ = differing(cpu, gpu, 1e-3f * s.voxelSize);
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
        const size_t differ = differing(cpu, gpu, 1e-3f * s.voxelSize);
        EXPECT_LE(differ, cpu.size() / 2000) << differ << " of " << cpu.size() << " differ";
    }
}

// RTSDF's per-frame regeneration with f_{t-1} kept on the device (accumulate) and the mesh posed
// there (pose), against the CPU's frames with a host history through the same LBVH code: a
// rigidly moving and a deforming mesh, then a restart that equals a fresh first frame.
TEST(GpuBake, DeviceAccumulationFollowsAMovingMeshAsTheCpu) {
    SKIP_WITHOUT_GPU();
    const TriangleMesh rest = load("bunny_npm.obj");
    const Bounds3 b = rest.bounds();
    SampleOptions so;
    so.resolution = 64;
    so.kind = GridKind::Dense;
    const GridShape s = gridShapeFor({b.lo - b.extent() * 0.25f, b.hi + b.extent() * 0.25f}, so);
    for (const bool deform : {false, true}) {
        SCOPED_TRACE(deform ? "deforming" : "moving");
        // The deforming mesh as bakeMeshGpu poses it: dipoles over the LBVH on the device.
        GpuMeshBaker baker(rest, deform ? GpuWinding::Lbvh : GpuWinding::MedianTree);
        RtsdfHistory cpuHistory;
        RtsdfOptions o;
        o.rays = 2;
        o.caster = RtsdfCaster::Lbvh;
        o.history = &cpuHistory;
        cpuHistory.alpha = 0.9f;
        for (int frame = 0; frame < 4; ++frame) {
            SCOPED_TRACE(frame);
            TriangleMesh mesh = rest;
            const Vec3 c = b.center();
            for (Vec3& p : mesh.positions)
                p = deform ? c + (p - c) * Vec3(1 + 0.04f * frame, 1 - 0.03f * frame, 1)
                           : p + Vec3(0.7f * frame * s.voxelSize, 0, 0.3f * frame * s.voxelSize);
            GpuBakeTimes times;
            if (frame > 0) baker.pose(mesh, &times);
            const std::vector<float> gpu = baker.accumulate(s, o, 0.9f, nullptr, nullptr, &times);
            const std::vector<float> cpu = bakeRtsdfSamples(mesh, MeshBvh(mesh), s, o);
            EXPECT_EQ(baker.accumulatedFrames(), cpuHistory.frames);
            if (frame > 0) {
                EXPECT_GT(times.poseMs, 0.0);
            }
            ASSERT_EQ(gpu.size(), cpu.size());
            const size_t differ = differing(cpu, gpu, 1e-3f * s.voxelSize);
            EXPECT_LE(differ, cpu.size() / 2000) << differ << " of " << cpu.size() << " differ";
        }
        // Starting from an empty host history forgets the frames: a fresh baker's first frame.
        const RtsdfHistory none{};
        const std::vector<float> restarted = baker.accumulate(s, o, 0.9f, &none);
        EXPECT_EQ(baker.accumulatedFrames(), 1);
        GpuMeshBaker fresh(rest, deform ? GpuWinding::Lbvh : GpuWinding::MedianTree);
        TriangleMesh last = rest;
        for (Vec3& p : last.positions)
            p = deform ? b.center() + (p - b.center()) * Vec3(1.12f, 0.91f, 1)
                       : p + Vec3(2.1f * s.voxelSize, 0, 0.9f * s.voxelSize);
        fresh.pose(last);
        const std::vector<float> first = fresh.accumulate(s, o, 0.9f);
        const size_t differ = differing(first, restarted, 1e-5f * s.voxelSize);
        EXPECT_LE(differ, first.size() / 10000) << differ << " of " << first.size() << " differ";
    }
}

// bakeMeshGpu's frames of an rtsdf mesh with a history keep the baker and f_{t-1} on the device
// (RtsdfHistory::device, `fine` empty) and give the CPU bake's grids through the same LBVH code;
// a frame the CPU bakes in between finds no host f_{t-1}, and the GPU continues from the host's.
TEST(GpuBake, RtsdfFramesOfBakeMeshGpuStayOnTheDevice) {
    SKIP_WITHOUT_GPU();
    const TriangleMesh rest = load("teapot.obj");
    MeshBakeOptions o;
    o.method = MeshBakeMethod::Rtsdf;
    o.sampling.resolution = 48;
    o.sampling.bandVoxels = 1e6f;
    o.rtsdf.rays = 3;
    o.rtsdf.caster = RtsdfCaster::Lbvh;
    const Bounds3 b = rest.bounds();
    o.shape = gridShapeFor({b.lo - b.extent() * 0.25f, b.hi + b.extent() * 0.25f}, o.sampling);
    RtsdfHistory gpuHistory, cpuHistory;
    gpuHistory.alpha = cpuHistory.alpha = 0.8f;
    for (int frame = 0; frame < 5; ++frame) {
        SCOPED_TRACE(frame);
        TriangleMesh mesh = rest;
        for (Vec3& p : mesh.positions) p.y += 0.5f * frame * o.shape->voxelSize;
        o.rtsdf.history = &gpuHistory;
        if (frame == 2) {
            // A frame on the CPU finds no host f_{t-1} and starts afresh, as does the CPU's
            // history here; the GPU's next frame continues from the host's.
            bakeMesh(mesh, o);
            EXPECT_EQ(gpuHistory.frames, 1);
            cpuHistory = RtsdfHistory();
            cpuHistory.alpha = 0.8f;
            o.rtsdf.history = &cpuHistory;
            bakeMesh(mesh, o);
            continue;
        }
        const Grid gpu = bakeMeshGpu(mesh, o).grid;
        o.rtsdf.history = &cpuHistory;
        const Grid cpu = bakeMesh(mesh, o).grid;
        EXPECT_EQ(gpuHistory.frames, cpuHistory.frames);
        EXPECT_TRUE(gpuHistory.fine.empty());
        EXPECT_NE(gpuHistory.device, nullptr);
        const std::vector<float> g = gpu.vertexSamples(), c = cpu.vertexSamples();
        ASSERT_EQ(g.size(), c.size());
        const size_t differ = differing(c, g, 1e-3f * o.shape->voxelSize);
        EXPECT_LE(differ, c.size() / 2000) << differ << " of " << c.size() << " differ";
    }
}

}  // namespace
}  // namespace sdft
