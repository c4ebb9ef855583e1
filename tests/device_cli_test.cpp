// `sdftrace render --device cpu|cuda|auto` as a user runs it (issue 14, docs/gpu.md). Without a
// GPU (CI, this build without CUDA) cuda is one clear error and auto renders on the CPU, saying
// why; with one, both render on it and agree with the CPU's image.
#include <gtest/gtest.h>

#include <cmath>

#include "cli_runner.h"
#include "sdftrace/gpu/gpu_device.h"

namespace sdft::e2e {
namespace {

const std::string kSize = " --width 96 --height 54 -q";

std::string example(const std::string& name) {
    return std::string(SDFT_SOURCE_DIR) + "/examples/" + name + ".json";
}

double meanAbsDifference(const std::vector<float>& a, const std::vector<float>& b) {
    if (a.size() != b.size() || a.empty()) return INFINITY;
    double sum = 0;
    for (size_t i = 0; i < a.size(); ++i) sum += std::fabs(a[i] - b[i]);
    return sum / static_cast<double>(a.size());
}

TEST(DeviceCli, CudaRendersOnTheGpuOrFailsWithOneLineAndNoOutput) {
    TempDir dir;
    const std::string out = dir.file("gpu.pfm");
    const RunResult r =
        runCli("render " + example("shadows") + " --device cuda -o " + out + kSize, dir);
    if (gpuInfo().present) {
        ASSERT_EQ(r.status, 0) << r.err;
        EXPECT_NE(r.err.find("GPU kernels"), std::string::npos) << r.err;
        const RunResult cpu =
            runCli("render " + example("shadows") + " -o " + dir.file("cpu.pfm") + kSize, dir);
        ASSERT_EQ(cpu.status, 0) << cpu.err;
        int w, h, c;
        EXPECT_LT(meanAbsDifference(readPfm(out, w, h, c), readPfm(dir.file("cpu.pfm"), w, h, c)),
                  2e-3);
        return;
    }
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(r.err.rfind("sdftrace: error: --device cuda: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(gpuInfo().why), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out));
    EXPECT_EQ(dir.count(), 0);
}

TEST(DeviceCli, AutoFallsBackToTheCpuAndSaysWhy) {
    TempDir dir;
    // Shadow maps only the CPU renders: auto takes the CPU on any machine.
    const RunResult mapped =
        runCli("render " + example("shadows") + " --shadow-method pcf --device auto -o " +
                   dir.file("pcf.pfm") + " --width 48 --height 27",
               dir);
    ASSERT_EQ(mapped.status, 0) << mapped.err;
    EXPECT_NE(mapped.err.find("--device auto: rendering on the CPU ("), std::string::npos)
        << mapped.err;
    if (gpuInfo().present) {
        EXPECT_NE(mapped.err.find("the GPU does not render shadow maps"), std::string::npos)
            << mapped.err;
    }
    // Without a GPU the plastic scene is the CPU's image bit for bit.
    const RunResult a = runCli(
        "render " + example("shadows") + " --device auto -o " + dir.file("auto.pfm") + kSize, dir);
    const RunResult c = runCli(
        "render " + example("shadows") + " --device cpu -o " + dir.file("cpu.pfm") + kSize, dir);
    ASSERT_EQ(a.status, 0) << a.err;
    ASSERT_EQ(c.status, 0) << c.err;
    int w, h, ch;
    const double mad = meanAbsDifference(readPfm(dir.file("auto.pfm"), w, h, ch),
                                         readPfm(dir.file("cpu.pfm"), w, h, ch));
    if (gpuInfo().present) {
        EXPECT_LT(mad, 2e-3);
    } else {
        EXPECT_EQ(mad, 0.0);
        EXPECT_EQ(readFile(dir.file("auto.pfm")), readFile(dir.file("cpu.pfm")));
    }
}

// Textures and RTSDF's hybrid mode (--primary-triangles) render on the GPU from the command
// line: no fallback line under auto, and the CPU's image within 2e-3 mean absolute difference.
TEST(DeviceCli, TexturesAndTrianglePrimariesRenderOnTheGpu) {
    if (!gpuInfo().present) GTEST_SKIP() << "no GPU: " << gpuInfo().why;
    TempDir dir;
    for (const std::string& args :
         {example("textures"), example("hybrid") + " --primary-triangles"}) {
        SCOPED_TRACE(args);
        const RunResult g = runCli(
            "render " + args + " --device auto -o " + dir.file("g.pfm") + " --width 96 --height 54",
            dir);
        ASSERT_EQ(g.status, 0) << g.err;
        EXPECT_EQ(g.err.find("rendering on the CPU"), std::string::npos) << g.err;
        const RunResult c = runCli("render " + args + " -o " + dir.file("c.pfm") + kSize, dir);
        ASSERT_EQ(c.status, 0) << c.err;
        int w, h, ch;
        EXPECT_LT(meanAbsDifference(readPfm(dir.file("g.pfm"), w, h, ch),
                                    readPfm(dir.file("c.pfm"), w, h, ch)),
                  2e-3);
    }
}

TEST(DeviceCli, CudaNamesWhatTheGpuDoesNotRender) {
    if (!gpuInfo().present) GTEST_SKIP() << "no GPU: " << gpuInfo().why;
    TempDir dir;
    const RunResult r =
        runCli("render " + example("shadows") + " --shadow-method evsm --device cuda -o " +
                   dir.file("g.png") + kSize,
               dir);
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("--device cuda: the GPU does not render shadow maps"), std::string::npos)
        << r.err;
    EXPECT_EQ(dir.count(), 0);
}

// `sdftrace bake mesh --device cuda|auto` (jfa and rtsdf bake on the GPU).
const std::string kMesh = std::string(SDFT_SOURCE_DIR) + "/data/meshes/suzanne.obj";

TEST(DeviceCli, BakeCudaRunsOnTheGpuOrFailsWithOneLineAndNoOutput) {
    TempDir dir;
    for (const char* method : {"jfa", "rtsdf"}) {
        SCOPED_TRACE(method);
        const std::string out = dir.file(std::string(method) + ".sdfg");
        const RunResult r = runCli(
            "bake " + kMesh + " --method " + method + " --res 32 --dense --device cuda -o " + out,
            dir);
        if (gpuInfo().present) {
            ASSERT_EQ(r.status, 0) << r.err;
            EXPECT_NE(r.err.find("(gpu)"), std::string::npos) << r.err;
            EXPECT_TRUE(std::filesystem::exists(out));
            continue;
        }
        EXPECT_EQ(r.status, 1);
        EXPECT_EQ(r.err.rfind("sdftrace: error: --device cuda: ", 0), 0u) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_FALSE(std::filesystem::exists(out));
    }
    if (!gpuInfo().present) {
        EXPECT_EQ(dir.count(), 0);
    }
}

TEST(DeviceCli, BakeCudaNamesWhatOnlyTheCpuBakes) {
    TempDir dir;
    const RunResult exact =
        runCli("bake " + kMesh + " --res 32 --device cuda -o " + dir.file("e.sdfg"), dir);
    EXPECT_EQ(exact.status, 1);
    EXPECT_EQ(exact.err,
              "sdftrace: error: --device cuda: --method exact runs on the CPU only (the GPU "
              "bakes jfa and rtsdf)\n");
    const RunResult parity = runCli("bake " + kMesh + " --method rtsdf --sign parity --res 32 " +
                                        "--device cuda -o " + dir.file("p.sdfg"),
                                    dir);
    EXPECT_EQ(parity.status, 1);
    EXPECT_NE(parity.err.find("--sign parity runs on the CPU only"), std::string::npos)
        << parity.err;
    EXPECT_EQ(dir.count(), 0);
}

TEST(DeviceCli, BakeAutoFallsBackToTheCpuAndSaysWhy) {
    TempDir dir;
    const RunResult exact =
        runCli("bake " + kMesh + " --res 24 --device auto -o " + dir.file("e.sdfg"), dir);
    ASSERT_EQ(exact.status, 0) << exact.err;
    EXPECT_NE(exact.err.find("--device auto: baking on the CPU (--method exact runs on the CPU "
                             "only"),
              std::string::npos)
        << exact.err;
    if (gpuInfo().present) return;
    // Without a GPU auto's jfa bake is the CPU's, byte for byte.
    const RunResult a = runCli(
        "bake " + kMesh + " --method jfa --res 24 --device auto -o " + dir.file("auto.sdfg"), dir);
    const RunResult c =
        runCli("bake " + kMesh + " --method jfa --res 24 -o " + dir.file("cpu.sdfg"), dir);
    ASSERT_EQ(a.status, 0) << a.err;
    ASSERT_EQ(c.status, 0) << c.err;
    EXPECT_NE(a.err.find("--device auto: baking on the CPU (" + gpuInfo().why + ")"),
              std::string::npos)
        << a.err;
    EXPECT_EQ(readFile(dir.file("auto.sdfg")), readFile(dir.file("cpu.sdfg")));
}

// With a GPU, the room's dynamic RTSDF mesh (the bending tube) is regenerated on it every frame
// (its rays through the LBVH, not Embree: a few rays differ on edges) and the frames match the
// CPU's.
TEST(DeviceCli, RtsdfMeshesOfAnAnimationBakeOnTheGpu) {
    if (!gpuInfo().present) GTEST_SKIP() << "no GPU: " << gpuInfo().why;
    TempDir dir;
    const std::string flags = " --time 0:0.1 --fps 20 --width 96 --height 54 -q";
    const RunResult gpu = runCli("render " + example("room") + " --device cuda --frame-pattern " +
                                     dir.file("g%02d.pfm") + flags,
                                 dir);
    const RunResult cpu = runCli("render " + example("room") + " --device cpu --frame-pattern " +
                                     dir.file("c%02d.pfm") + flags,
                                 dir);
    ASSERT_EQ(gpu.status, 0) << gpu.err;
    ASSERT_EQ(cpu.status, 0) << cpu.err;
    for (const char* frame : {"00", "01"}) {
        int w, h, c;
        EXPECT_LT(meanAbsDifference(readPfm(dir.file(std::string("g") + frame + ".pfm"), w, h, c),
                                    readPfm(dir.file(std::string("c") + frame + ".pfm"), w, h, c)),
                  1e-2)
            << "frame " << frame;
    }
}

// The viewer takes --device too: without a GPU, cuda is one line before any window opens (the
// check runs before the viewer, so a build without one answers the same). An mpirun job refuses
// cuda with one line (each rank renders its tiles on its CPU).
TEST(DeviceCli, TheViewerAsksForTheGpuAsRenderDoes) {
    if (gpuInfo().present) GTEST_SKIP() << "a GPU is present: the viewer would open a window";
    TempDir dir;
    const RunResult r = runCli("view " + example("shadows") + " --device cuda", dir);
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(r.err.rfind("sdftrace: error: --device cuda: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(gpuInfo().why), std::string::npos) << r.err;
    const RunResult bad = runCli("view " + example("shadows") + " --device tpu", dir);
    EXPECT_NE(bad.status, 0);
    EXPECT_NE(bad.err.find("--device"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace sdft::e2e
