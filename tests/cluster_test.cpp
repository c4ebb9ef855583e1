// mpirun -np N sdftrace render|bake on this machine (docs/cluster.md): the outputs of 2 and more
// ranks against a single process's bit for bit, and failures on one rank that stop the whole job
// with one error and no output. Skipped where the build has no MPI (SDFT_MPI).
#include <gtest/gtest.h>

#include "cli_runner.h"
#include "sdftrace/gpu/gpu_device.h"

namespace sdft::e2e {
namespace {

#ifdef SDFT_MPIRUN
constexpr bool kHaveMpi = true;
const std::string kMpirun = SDFT_MPIRUN;
#else
constexpr bool kHaveMpi = false;
const std::string kMpirun;
#endif

const std::string kSource = SDFT_SOURCE_DIR;
const std::string kCli = SDFT_CLI_PATH;

// Open MPI refuses root without the first two (CI runs as root); oversubscription lets 3 to 5
// ranks share this machine's 2 cores; shared-memory messages without the single-copy mechanism
// (CMA), which containers without ptrace permission refuse.
const std::string kMpiEnv =
    "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
    "OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_btl_vader_single_copy_mechanism=none ";

// Runs a whole command line (mpirun ...) with output captured outside `dir`.
RunResult runShell(const std::string& cmd) {
    TempDir logs;
    const std::string out = logs.file("stdout"), err = logs.file("stderr");
    const int raw = std::system((cmd + " >" + out + " 2>" + err + " </dev/null").c_str());
    RunResult r;
    r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    r.out = readFile(out);
    r.err = readFile(err);
    return r;
}

RunResult mpirun(int ranks, const std::string& args, const std::string& env = "") {
    return runShell(kMpiEnv + env + kMpirun + " -np " + std::to_string(ranks) + " " + kCli + " " +
                    args);
}

RunResult single(const std::string& args) { return runShell(kCli + " " + args); }

#define REQUIRE_MPI() \
    if (!kHaveMpi) GTEST_SKIP() << "this build has no MPI (SDFT_MPI: libopenmpi-dev not found)"

// The number of lines of `text` that contain `what`.
int linesWith(const std::string& text, const std::string& what) {
    int n = 0;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) n += line.find(what) != std::string::npos;
    return n;
}

void expectSameFile(const std::string& a, const std::string& b) {
    const std::string x = readFile(a), y = readFile(b);
    ASSERT_FALSE(x.empty()) << a;
    EXPECT_TRUE(x == y) << a << " and " << b << " differ";
}

// Renders with one process and with `ranks`; every output compared byte for byte.
void expectSameRender(const TempDir& dir, int ranks, const std::string& args) {
    const std::string one = "-q -o " + dir.file("one.pfm") +
                            " --aov depth=" + dir.file("one-depth.pfm") +
                            " --aov steps=" + dir.file("one-steps.pfm");
    const std::string many = "-q -o " + dir.file("many.pfm") +
                             " --aov depth=" + dir.file("many-depth.pfm") +
                             " --aov steps=" + dir.file("many-steps.pfm");
    const RunResult a = single("render " + args + " " + one);
    ASSERT_EQ(a.status, 0) << a.err;
    const RunResult b = mpirun(ranks, "render " + args + " " + many);
    ASSERT_EQ(b.status, 0) << b.err;
    EXPECT_NE(b.err.find("on " + std::to_string(ranks) + " ranks"), std::string::npos) << b.err;
    expectSameFile(dir.file("one.pfm"), dir.file("many.pfm"));
    expectSameFile(dir.file("one-depth.pfm"), dir.file("many-depth.pfm"));
    expectSameFile(dir.file("one-steps.pfm"), dir.file("many-steps.pfm"));
}

TEST(Cluster, StillsAreTheSingleProcessImagesBitForBit) {
    REQUIRE_MPI();
    TempDir dir;
    const std::string small = " --width 120 --height 72";
    // Analytic CSG with soft shadows; Whitted glass; a grid traced by the DDA; the demo scene.
    expectSameRender(dir, 2, kSource + "/examples/csg.json" + small);
    expectSameRender(dir, 3, kSource + "/examples/jewel.json" + small);
    expectSameRender(dir, 2, kSource + "/examples/rock.json" + small);
    expectSameRender(dir, 4, small);
}

TEST(Cluster, PathTracingAndAccumulatedFramesAreBitForBit) {
    REQUIRE_MPI();
    TempDir dir;
    expectSameRender(dir, 2,
                     kSource + "/examples/path.json --width 64 --height 40 --spp 3 --threads 1");
    // Accumulated frames: each one's tiles across the ranks, blended on rank 0; the orbit
    // reprojects through depth.
    expectSameRender(dir, 2, kSource + "/examples/shadows.json --width 80 --height 48 --frames 3");
    expectSameRender(dir, 3,
                     kSource + "/examples/csg.json --width 80 --height 48 --frames 3 --orbit 4");
}

// A --time range: independent frames dealt whole to the ranks; with --taa (frames depend on the
// ones before) each frame's tiles across the ranks.
TEST(Cluster, AnimationsAreTheSingleProcessFramesBitForBit) {
    REQUIRE_MPI();
    TempDir dir;
    const std::string scene = kSource +
                              "/examples/animated.json --time 0:0.4 --fps 10 "
                              "--width 64 --height 40 -q ";
    for (const std::string& mode : {std::string(""), std::string("--taa ")}) {
        const RunResult a =
            single("render " + scene + mode + "--frame-pattern " + dir.file("one-%02d.pfm") +
                   " --aov motion=" + dir.file("one-m%02d.pfm"));
        ASSERT_EQ(a.status, 0) << a.err;
        const RunResult b =
            mpirun(2, "render " + scene + mode + "--frame-pattern " + dir.file("many-%02d.pfm") +
                          " --aov motion=" + dir.file("many-m%02d.pfm"));
        ASSERT_EQ(b.status, 0) << b.err;
        for (int i = 0; i < 4; ++i) {
            char name[32];
            std::snprintf(name, sizeof name, "%02d.pfm", i);
            expectSameFile(dir.file(std::string("one-") + name),
                           dir.file(std::string("many-") + name));
            expectSameFile(dir.file(std::string("one-m") + name),
                           dir.file(std::string("many-m") + name));
        }
        EXPECT_EQ(linesWith(b.err, "4 frames"), 1) << b.err;
    }
    // The room's meshes regenerated by RTSDF with temporal accumulation: its histories evolve on
    // every rank alike.
    const std::string room = "render " + kSource +
                             "/examples/room.json --time 0:0.2 --fps 10 --width 48 --height 32 -q "
                             "--frame-pattern ";
    ASSERT_EQ(single(room + dir.file("room-one-%d.pfm")).status, 0);
    const RunResult r = mpirun(2, room + dir.file("room-many-%d.pfm"));
    ASSERT_EQ(r.status, 0) << r.err;
    for (int i = 0; i < 2; ++i)
        expectSameFile(dir.file("room-one-" + std::to_string(i) + ".pfm"),
                       dir.file("room-many-" + std::to_string(i) + ".pfm"));
}

// The .sdfg every rank wrote holds the single-process bake's samples: converted to the raw
// version 1 (the samples of every surface block, as one process stores them) both are the same
// bytes, and the distributed file saved again is the single-process file byte for byte.
void expectSameGrid(const TempDir& dir, const std::string& one, const std::string& many) {
    for (const char* f : {"one-raw.sdfg", "many-raw.sdfg", "many-again.sdfg"})
        std::filesystem::remove(dir.file(f));
    ASSERT_EQ(single("convert " + one + " " + dir.file("one-raw.sdfg") + " --uncompressed").status,
              0);
    const RunResult r =
        single("convert " + many + " " + dir.file("many-raw.sdfg") + " --uncompressed");
    ASSERT_EQ(r.status, 0) << r.err;
    ASSERT_EQ(single("convert " + many + " " + dir.file("many-again.sdfg")).status, 0);
    expectSameFile(dir.file("one-raw.sdfg"), dir.file("many-raw.sdfg"));
    expectSameFile(one, dir.file("many-again.sdfg"));
}

// Open and closed meshes, 2 to 5 ranks, both block sizes, both sign methods, sections small
// enough that every chunk spans several ranks' parts and large enough that ranks own chunks: the
// .sdfg that every rank writes holds the single-process grid's samples; a .vdb (gathered on rank
// 0) differs only in the UUID of its header.
TEST(Cluster, SparseExactBakesAreTheSingleProcessGridBitForBit) {
    REQUIRE_MPI();
    TempDir dir;
    struct Case {
        std::string mesh, flags;
        int ranks;
    };
    const std::vector<Case> cases = {
        {"stanford-bunny.obj", "--res 80", 2},
        {"elephant-with-holes.obj", "--res 72 --block 8 --band 4", 3},
        {"teapot.obj", "--res 64 --sign parity", 2},
        {"suzanne.obj", "--res 20", 5},          // more ranks than the grid has tile layers
        {"stanford-bunny.obj", "--res 320", 4},  // 7 MiB of samples: chunks in several ranks
    };
    for (const Case& c : cases) {
        const std::string args =
            "bake " + kSource + "/data/meshes/" + c.mesh + " " + c.flags + " -q";
        const RunResult a = single(args + " -o " + dir.file("one.sdfg"));
        ASSERT_EQ(a.status, 0) << a.err;
        const RunResult b = mpirun(c.ranks, args + " -o " + dir.file("many.sdfg"));
        ASSERT_EQ(b.status, 0) << b.err;
        EXPECT_NE(b.err.find(std::to_string(c.ranks) + " ranks, "), std::string::npos) << b.err;
        EXPECT_NE(b.err.find("written by every rank"), std::string::npos) << b.err;
        SCOPED_TRACE(c.mesh + " " + c.flags);
        expectSameGrid(dir, dir.file("one.sdfg"), dir.file("many.sdfg"));
    }
    // --verify reads the whole grid: assembled on rank 0, the single-process file itself.
    const std::string verify =
        "bake " + kSource + "/data/meshes/teapot.obj --res 48 --verify -q -o ";
    ASSERT_EQ(single(verify + dir.file("one.sdfg")).status, 0);
    const RunResult v = mpirun(2, verify + dir.file("many.sdfg"));
    ASSERT_EQ(v.status, 0) << v.err;
    EXPECT_NE(v.err.find("2 ranks, one slab each"), std::string::npos) << v.err;
    expectSameFile(dir.file("one.sdfg"), dir.file("many.sdfg"));
    const std::string args = "bake " + kSource + "/data/meshes/suzanne.obj --res 48 -q";
    ASSERT_EQ(single(args + " -o " + dir.file("one.vdb")).status, 0);
    ASSERT_EQ(mpirun(2, args + " -o " + dir.file("many.vdb")).status, 0);
    const std::string x = readFile(dir.file("one.vdb")), y = readFile(dir.file("many.vdb"));
    ASSERT_EQ(x.size(), y.size());
    size_t differ = 0;
    for (size_t i = 0; i < x.size(); ++i)
        if (x[i] != y[i]) {
            ++differ;
            // OpenVDB's header: magic, versions, a flag, then the file's 36-character UUID.
            EXPECT_TRUE(i >= 21 && i < 57) << "byte " << i;
        }
    EXPECT_GT(differ, 0u);  // two files, two UUIDs
}

// Every rank stops with a non-zero status; rank 0 prints the failing rank's error once; nothing
// is written.
void expectJobFailed(const RunResult& r, const std::string& error, const TempDir& dir, int files) {
    EXPECT_NE(r.status, 0) << r.err;
    EXPECT_EQ(linesWith(r.err, "sdftrace: error:"), 1) << r.err;
    EXPECT_EQ(linesWith(r.err, "sdftrace: error: rank 1: " + error), 1) << r.err;
    EXPECT_EQ(dir.count(), files) << "an output or temporary file was left";
}

TEST(Cluster, AFailureOnOneRankStopsEveryRankWithOneErrorAndNoOutput) {
    REQUIRE_MPI();
    TempDir dir;
    const std::string inject = "-x SDFTRACE_INJECT_FAILURE ";
    // In the middle of a render: rank 1 fails at its second chunk of tiles (docs/cluster.md's
    // test hook), after rank 0 has some of the image.
    const std::string csg = kSource + "/examples/csg.json --width 160 --height 96 -q";
    RunResult r = runShell(kMpiEnv + "SDFTRACE_INJECT_FAILURE=1:2 " + kMpirun + " " + inject +
                           "-np 2 " + kCli + " render " + csg + " -o " + dir.file("out.png"));
    expectJobFailed(r, "injected failure", dir, 0);
    // A chunk rank 1 never reaches (rank 0 deals them all first): it fails when the round ends,
    // so that the hook fires however the work was shared.
    r = runShell(kMpiEnv + "SDFTRACE_INJECT_FAILURE=1:1000 " + kMpirun + " " + inject + "-np 2 " +
                 kCli + " render " + csg + " -o " + dir.file("out.png"));
    expectJobFailed(r, "injected failure", dir, 0);
    // In a bake's slab, and in the frames of an animation (a video: no file until the last).
    r = runShell(kMpiEnv + "SDFTRACE_INJECT_FAILURE=1 " + kMpirun + " " + inject + "-np 2 " + kCli +
                 " bake " + kSource + "/data/meshes/teapot.obj --res 48 -q -o " +
                 dir.file("out.sdfg"));
    expectJobFailed(r, "injected failure", dir, 0);
    r = runShell(kMpiEnv + "SDFTRACE_INJECT_FAILURE=1 " + kMpirun + " " + inject + "-np 2 " + kCli +
                 " render " + kSource +
                 "/examples/animated.json --time 0:0.5 --fps 10 --width 48 --height 32 -q -o " +
                 dir.file("out.mp4"));
    expectJobFailed(r, "injected failure", dir, 0);
    // A file missing on one node: rank 1 runs in a directory without the scene.
    TempDir a, b;
    std::filesystem::copy_file(kSource + "/examples/csg.json", a.file("scene.json"));
    r = runShell(kMpiEnv + kMpirun + " -np 1 -wdir " + a.path() + " " + kCli +
                 " render scene.json -q -o " + a.file("out.png") + " : -np 1 -wdir " + b.path() +
                 " " + kCli + " render scene.json -q -o " + a.file("out.png"));
    expectJobFailed(r, "scene.json: cannot open scene file", a, 1);
    // Not enough memory on one node: rank 1's budget refuses the bake's arrays.
    const std::string bake =
        " bake " + kSource + "/data/meshes/teapot.obj --res 128 -q -o " + dir.file("out.sdfg");
    r = runShell(kMpiEnv + kMpirun + " -np 1 " + kCli + bake + " : -np 1 " + kCli +
                 " --max-memory 64K" + bake);
    expectJobFailed(r, "", dir, 0);
    EXPECT_NE(r.err.find("budget of 64 KiB"), std::string::npos) << r.err;
    // A budget that passes the estimate but not the slab's arrays: rank 1 runs out mid-bake.
    const std::string large =
        " bake " + kSource + "/data/meshes/teapot.obj --res 512 -q -o " + dir.file("out.sdfg");
    r = runShell(kMpiEnv + kMpirun + " -np 1 " + kCli + large + " : -np 1 " + kCli +
                 " --max-memory 10M" + large);
    expectJobFailed(r, "out of memory (an allocation over the memory budget of 10 MiB", dir, 0);
}

// A rank that dies (SIGKILL, as the kernel's OOM killer sends) while baking its slab, or while
// the ranks write the file (rank 0, which made the temporary file, or another): mpirun ends the
// job, and no output or temporary file is left.
TEST(Cluster, ARankKilledMidBakeLeavesNoFile) {
    REQUIRE_MPI();
    TempDir dir;
    for (const char* when : {"1:kill", "0:kill-write", "2:kill-write"}) {
        SCOPED_TRACE(when);
        const RunResult r =
            runShell(kMpiEnv + "SDFTRACE_INJECT_FAILURE=" + when + " " + kMpirun +
                     " -x SDFTRACE_INJECT_FAILURE -np 3 " + kCli + " bake " + kSource +
                     "/data/meshes/teapot.obj --res 64 -q -o " + dir.file("out.sdfg"));
        EXPECT_NE(r.status, 0) << r.err;
        EXPECT_EQ(dir.count(), 0) << "an output or temporary file was left";
    }
}

// A grid larger than one rank's memory budget: one process is refused, four ranks under the same
// budget each bake a quarter and write it, and the file holds the single-process samples.
TEST(Cluster, ABakeBeyondOneRanksBudgetCompletesOnSeveralRanks) {
    REQUIRE_MPI();
    TempDir dir;
    const std::string bake = "bake " + kSource + "/data/meshes/teapot.obj --res 512 -q -o ";
    const RunResult refused = single("--max-memory 16M " + bake + dir.file("one.sdfg"));
    EXPECT_NE(refused.status, 0);
    EXPECT_NE(refused.err.find("memory budget of 16 MiB"), std::string::npos) << refused.err;
    const RunResult r = mpirun(4, "--max-memory 16M " + bake + dir.file("many.sdfg"));
    ASSERT_EQ(r.status, 0) << r.err;
    ASSERT_EQ(single(bake + dir.file("one.sdfg")).status, 0);
    const RunResult info = single("info " + dir.file("one.sdfg"));
    ASSERT_EQ(info.status, 0);
    const size_t at = info.out.find("memory:");
    ASSERT_NE(at, std::string::npos) << info.out;
    EXPECT_GT(std::stod(info.out.substr(info.out.find("about", at) + 6)), 16.0) << info.out;
    expectSameGrid(dir, dir.file("one.sdfg"), dir.file("many.sdfg"));
}

// One GPU per rank: every rank asks for its own (the machine's GPUs in turn), as one process
// asks. Without a GPU, --device cuda stops the job before any work with one error line that says
// why, and writes nothing; auto renders on the ranks' CPUs, the still's tiles and the
// animation's frames shared as without --device, saying so once.
TEST(Cluster, EveryRankAsksForItsGpuAsOneProcessDoes) {
    REQUIRE_MPI();
    if (gpuInfo().present) GTEST_SKIP() << "a GPU is present: cuda would render";
    TempDir dir;
    const std::string csg = "render " + kSource + "/examples/csg.json --width 64 --height 40 ";
    const RunResult cuda = mpirun(2, csg + "--device cuda -o " + dir.file("out.png"));
    EXPECT_NE(cuda.status, 0);
    EXPECT_EQ(linesWith(cuda.err, "sdftrace: error:"), 1) << cuda.err;
    EXPECT_EQ(linesWith(cuda.err, "--device cuda: " + gpuInfo().why), 1) << cuda.err;
    EXPECT_EQ(dir.count(), 0) << "an output or temporary file was left";

    ASSERT_EQ(single(csg + "-q -o " + dir.file("one.pfm")).status, 0);
    const RunResult still = mpirun(2, csg + "--device auto -o " + dir.file("many.pfm"));
    ASSERT_EQ(still.status, 0) << still.err;
    EXPECT_EQ(linesWith(still.err, "--device auto: rendering on the CPU"), 1) << still.err;
    EXPECT_NE(still.err.find("on 2 ranks"), std::string::npos) << still.err;
    expectSameFile(dir.file("one.pfm"), dir.file("many.pfm"));

    // Bakes: a method the GPU bakes runs on rank 0 alone, choosing its device as one process
    // does; the sparse exact bake, split across the ranks, runs on their CPUs (the GPU does not
    // bake it), refused under cuda with the single process's reason.
    const std::string jfa = "bake " + kSource + "/data/meshes/suzanne.obj --res 32 --method jfa ";
    const RunResult bakeCuda = mpirun(2, jfa + "--device cuda -o " + dir.file("jfa.sdfg"));
    EXPECT_NE(bakeCuda.status, 0);
    EXPECT_EQ(linesWith(bakeCuda.err, "sdftrace: error:"), 1) << bakeCuda.err;
    EXPECT_EQ(linesWith(bakeCuda.err, "--device cuda: " + gpuInfo().why), 1) << bakeCuda.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("jfa.sdfg")));
    ASSERT_EQ(single(jfa + "-q -o " + dir.file("jfa-one.sdfg")).status, 0);
    const RunResult bakeAuto = mpirun(2, jfa + "--device auto -o " + dir.file("jfa-many.sdfg"));
    ASSERT_EQ(bakeAuto.status, 0) << bakeAuto.err;
    EXPECT_EQ(linesWith(bakeAuto.err, "--device auto: baking on the CPU"), 1) << bakeAuto.err;
    expectSameFile(dir.file("jfa-one.sdfg"), dir.file("jfa-many.sdfg"));
    const RunResult exactCuda =
        mpirun(2, "bake " + kSource + "/data/meshes/suzanne.obj --res 32 --device cuda -o " +
                      dir.file("exact.sdfg"));
    EXPECT_NE(exactCuda.status, 0);
    EXPECT_EQ(linesWith(exactCuda.err, "sdftrace: error:"), 1) << exactCuda.err;
    EXPECT_EQ(linesWith(exactCuda.err, "runs on the CPU only"), 1) << exactCuda.err;

    const std::string frames = "render " + kSource +
                               "/examples/animated.json --time 0:0.2 --fps 10 --width 48 "
                               "--height 32 --frame-pattern ";
    ASSERT_EQ(single(frames + dir.file("one-%d.pfm") + " -q").status, 0);
    const RunResult dealt = mpirun(2, frames + dir.file("many-%d.pfm") + " --device auto");
    ASSERT_EQ(dealt.status, 0) << dealt.err;
    EXPECT_EQ(linesWith(dealt.err, "--device auto: rendering on the CPU"), 1) << dealt.err;
    for (int i = 0; i < 2; ++i)
        expectSameFile(dir.file("one-" + std::to_string(i) + ".pfm"),
                       dir.file("many-" + std::to_string(i) + ".pfm"));
}

// Without mpirun nothing changes: the summary names threads, not ranks.
TEST(Cluster, WithoutMpirunTheJobIsOneProcess) {
    TempDir dir;
    const RunResult r = single("render --width 32 --height 24 -o " + dir.file("x.png"));
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.err.find("ranks"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace sdft::e2e
