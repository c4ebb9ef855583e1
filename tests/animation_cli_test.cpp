// Rendering a scene's animation through the CLI (issue 16): --time T renders an instant, --time
// A:B --fps F the frames of a range through --frame-pattern; bad time flags are one clear line and
// leave no file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "cli_runner.h"
#include "sdftrace/io/video_writer.h"

namespace sdft::e2e {
namespace {

// A ball crossing the view from x = -1 to x = 1 in one second.
const char* kMovingBall = R"({
  "camera": {"eye": [0, 0, 5], "target": [0, 0, 0], "width": 40, "height": 24, "fov": 40},
  "lights": [{"type": "directional", "direction": [-1, -1, -1]}],
  "objects": [{"type": "sphere", "radius": 0.5,
               "translate": {"keyframes": [{"time": 0, "value": [-1, 0, 0]},
                                           {"time": 1, "value": [1, 0, 0]}]}}]
})";

// Mean column of the pixels a depth image hits.
double hitColumn(const std::string& pfm) {
    int w = 0, h = 0, c = 0;
    const std::vector<float> depth = readPfm(pfm, w, h, c);
    double sum = 0, n = 0;
    for (int i = 0; i < w * h; ++i)
        if (std::isfinite(depth[static_cast<size_t>(i)])) {
            sum += i % w;
            ++n;
        }
    return n > 0 ? sum / n : -1;
}

TEST(Animation, ARangeWritesEachFrameThroughThePatterns) {
    TempDir dir;
    const std::string scene = dir.write("ball.json", kMovingBall);
    RunResult r = runCli("render " + scene + " --time 0:1 --fps 4 --frame-pattern " +
                             dir.file("f_%02d.png") + " --aov depth=" + dir.file("d_%02d.pfm"),
                         dir);
    ASSERT_EQ(r.status, 0) << r.err;
    double previous = -1;
    for (int k = 0; k < 4; ++k) {  // t = 0, 0.25, 0.5, 0.75 (the range's end is not a frame)
        char name[32];
        std::snprintf(name, sizeof name, "f_%02d.png", k);
        EXPECT_TRUE(std::filesystem::exists(dir.file(name))) << name;
        std::snprintf(name, sizeof name, "d_%02d.pfm", k);
        const double column = hitColumn(dir.file(name));
        EXPECT_GT(column, previous + 3) << "frame " << k << ": the ball moves right";
        previous = column;
    }
    EXPECT_FALSE(std::filesystem::exists(dir.file("f_04.png")));
    EXPECT_EQ(dir.count(), 1 + 8);  // the scene, 4 images, 4 depths
    EXPECT_NE(r.err.find("4 frames (t = 0 to 0.75 s at 4 fps)"), std::string::npos) << r.err;

    // Frames keep their numbers on the timeline; an instant renders what its frame showed.
    TempDir later;
    r = runCli(
        "render " + scene + " --time 0.5:1 --fps 4 -q --frame-pattern " + later.file("f_%02d.png"),
        later);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(std::filesystem::exists(later.file("f_02.png")));
    EXPECT_TRUE(std::filesystem::exists(later.file("f_03.png")));
    EXPECT_EQ(later.count(), 2);
    r = runCli("render " + scene + " --time 0.5 -q -o " + later.file("still.png"), later);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(readFile(later.file("still.png")), readFile(dir.file("f_02.png")));
}

TEST(Animation, ARangeCanBeWrittenAsAVideo) {
    if (!VideoWriter::available()) GTEST_SKIP() << "this build has no FFmpeg";
    TempDir dir;
    const std::string scene = dir.write("ball.json", kMovingBall);
    RunResult r =
        runCli("render " + scene + " -q --time 0:1 --fps 8 -o " + dir.file("ball.mp4"), dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const VideoInfo info = probeVideo(dir.file("ball.mp4"));
    EXPECT_EQ(info.frames, 8);
    EXPECT_EQ(info.width, 40);
    EXPECT_EQ(info.height, 24);
    EXPECT_EQ(info.codec, "h264");
    EXPECT_EQ(dir.count(), 2);  // the scene and the video, no frame images
    // A video path needs a range; an image path with a range is refused.
    r = runCli("render " + scene + " -q --time 0.5 -o " + dir.file("still.mp4"), dir);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("--output"), std::string::npos) << r.err;
    EXPECT_EQ(dir.count(), 2);
}

// FFmpeg's encoder is a plugin (docs/decisions/0020-video-as-a-plugin.md): the executable loads
// no FFmpeg library at start; without the plugin a video fails with one line naming it and leaves
// no file, and frame images still render.
TEST(Animation, VideoIsAPluginLoadedOnlyWhenWritten) {
    if (!VideoWriter::available()) GTEST_SKIP() << "this build has no FFmpeg";
    const std::string libs = librariesLoadedAtStart();
    EXPECT_NE(libs.find("libtbb"), std::string::npos) << libs;
    for (const char* lib : {"libavformat", "libavcodec", "libswscale"})
        EXPECT_EQ(libs.find(lib), std::string::npos) << lib << " in\n" << libs;

    TempDir dir;
    const std::string scene = dir.write("ball.json", kMovingBall);
    setenv("SDFT_PLUGIN_DIR", dir.file("no-plugins-here").c_str(), 1);
    const RunResult video =
        runCli("render " + scene + " -q --time 0:1 --fps 4 -o " + dir.file("ball.mp4"), dir);
    const RunResult frames = runCli(
        "render " + scene + " -q --time 0:1 --fps 2 --frame-pattern " + dir.file("f%02d.png"), dir);
    unsetenv("SDFT_PLUGIN_DIR");
    EXPECT_NE(video.status, 0);
    EXPECT_NE(video.err.find("libsdftrace_video.so not found"), std::string::npos) << video.err;
    EXPECT_EQ(std::count(video.err.begin(), video.err.end(), '\n'), 1) << video.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("ball.mp4")));
    EXPECT_EQ(frames.status, 0) << frames.err;
    EXPECT_TRUE(std::filesystem::exists(dir.file("f00.png")));
    EXPECT_TRUE(std::filesystem::exists(dir.file("f01.png")));
}

// bake and mesh take an instant too: a keyframed scene at t gives the same file as the static
// scene holding its values at t.
TEST(Animation, BakeAndMeshTakeAnInstant) {
    TempDir dir;
    const std::string animated = dir.write("grow.json", R"({"objects": [{"type": "sphere",
        "radius": {"keyframes": [{"time": 0, "value": 0.5}, {"time": 2, "value": 1.5}]}}]})");
    const std::string still =
        dir.write("still.json", R"({"objects": [{"type": "sphere", "radius": 1}]})");
    for (const char* command : {"bake", "mesh"}) {
        const std::string ext = std::string(command) == "bake" ? ".sdfg" : ".ply";
        const std::string a = dir.file(std::string(command) + "_t1" + ext),
                          b = dir.file(std::string(command) + "_still" + ext);
        const std::string common = " -q --res 32 --bounds -2,-2,-2,2,2,2";
        const std::string bounds = std::string(command) == "bake" ? common : " -q --res 32";
        RunResult r =
            runCli(std::string(command) + " " + animated + " --time 1" + bounds + " -o " + a, dir);
        ASSERT_EQ(r.status, 0) << command << ": " << r.err;
        r = runCli(std::string(command) + " " + still + bounds + " -o " + b, dir);
        ASSERT_EQ(r.status, 0) << command << ": " << r.err;
        EXPECT_EQ(readFile(a), readFile(b)) << command;
        // Bad: an instant of a mesh.
        r = runCli(std::string(command) + " " + std::string(SDFT_SOURCE_DIR) +
                       "/data/meshes/teapot.obj --time 1 -q -o " + dir.file("x" + ext),
                   dir);
        EXPECT_NE(r.status, 0) << command;
        EXPECT_NE(r.err.find("--time: "), std::string::npos) << command << ": " << r.err;
        EXPECT_FALSE(std::filesystem::exists(dir.file("x" + ext)));
    }
}

// Mean motion vector (x, y) over the pixels a depth image hits; the background's must be zero.
std::pair<double, double> meanMotion(const std::string& motionPfm, const std::string& depthPfm) {
    int w = 0, h = 0, c = 0, dw = 0, dh = 0, dc = 0;
    const std::vector<float> motion = readPfm(motionPfm, w, h, c);
    const std::vector<float> depth = readPfm(depthPfm, dw, dh, dc);
    EXPECT_EQ(c, 3);
    EXPECT_EQ(w * h, dw * dh);
    double mx = 0, my = 0, n = 0;
    for (int i = 0; i < w * h; ++i) {
        const size_t j = static_cast<size_t>(i);
        if (!std::isfinite(depth[j])) {
            EXPECT_EQ(motion[3 * j], 0.0f);  // the background stays
            continue;
        }
        mx += motion[3 * j];
        my += motion[3 * j + 1];
        ++n;
    }
    EXPECT_GT(n, 20);
    return {mx / std::max(1.0, n), my / std::max(1.0, n)};
}

// The motion AOV points from each pixel to where its surface was one frame earlier: the ball
// moves 0.5 units right per frame at 4 fps, 3.3 pixels at its distance; --taa blends the frames.
TEST(Animation, MotionVectorsFollowTheBallAndTaaBlendsTheFrames) {
    TempDir dir;
    const std::string scene = dir.write("ball.json", kMovingBall);
    RunResult r = runCli("render " + scene + " --time 0:1 --fps 4 --taa --frame-pattern " +
                             dir.file("f_%02d.png") + " --aov motion=" + dir.file("m_%02d.pfm") +
                             " --aov depth=" + dir.file("d_%02d.pfm"),
                         dir);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.err.find("TAA: "), std::string::npos) << r.err;
    const double pixelsPerUnit = 24 / (2 * 5 * std::tan(20 * 3.14159265 / 180));
    // Frame 0 (t = 0) has none: before its first key the ball stands still (clamped).
    for (int k = 1; k < 4; ++k) {
        char m[32], d[32];
        std::snprintf(m, sizeof m, "m_%02d.pfm", k);
        std::snprintf(d, sizeof d, "d_%02d.pfm", k);
        const auto [mx, my] = meanMotion(dir.file(m), dir.file(d));
        EXPECT_NEAR(mx, -0.5 * pixelsPerUnit, 0.15 * pixelsPerUnit) << "frame " << k;
        EXPECT_NEAR(my, 0, 0.1) << "frame " << k;
    }
    // One instant: the motion from the frame before it.
    r = runCli("render " + scene + " -q --time 0.5 --fps 4 -o " + dir.file("s.png") +
                   " --aov motion=" + dir.file("s.pfm") + " --aov depth=" + dir.file("sd.pfm"),
               dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const auto [mx, my] = meanMotion(dir.file("s.pfm"), dir.file("sd.pfm"));
    EXPECT_NEAR(mx, -0.5 * pixelsPerUnit, 0.15 * pixelsPerUnit);
    EXPECT_NEAR(my, 0, 0.1);
}

TEST(Animation, BadTimeFlagsAreOneClearLineAndLeaveNoFile) {
    TempDir dir;
    const std::string scene = dir.write("ball.json", kMovingBall);
    const std::string pattern = " --frame-pattern " + dir.file("f_%02d.png");
    const struct {
        std::string args, expected;
    } cases[] = {
        {"--time soon" + pattern, "--time soon: expected a time T or a range A:B in seconds"},
        {"--time 1:" + pattern, "--time 1:: expected a time T or a range A:B"},
        {"--time 2:1" + pattern, "--time 2:1: the range ends before it starts"},
        {"--time nan" + pattern, "--time nan: expected a time T or a range A:B"},
        {"--time 0:1",
         "--time 0:1: a time range renders one image per frame; give --frame-pattern"},
        {"--time 0:1 -o " + dir.file("x.png") + pattern,
         "--output " + dir.file("x.png") + ": a time range writes its frames through"},
        {"--time 0:1 --aov depth=" + dir.file("d.pfm") + pattern,
         "--aov depth " + dir.file("d.pfm") + ": expected one frame-number field"},
        {"--time 0:1 --orbit 2" + pattern, "--orbit: cannot be combined with a --time range"},
        {"--time 0:100000 --fps 1000" + pattern, "a range renders at most 1000000 frames"},
        {"--time 0:1 --fps 0" + pattern, "--fps"},
        {"--taa -o " + dir.file("x.png"), "--taa: accumulates across the frames of a --time A:B"},
        {"--time 0:1 --taa --frames 4" + pattern, "--taa: accumulates one jittered frame per"},
        {"--time 0:1 --taa --taa-motion sideways" + pattern, "--taa-motion"},
    };
    for (const auto& c : cases) {
        RunResult r = runCli("render " + scene + " -q " + c.args, dir);
        EXPECT_NE(r.status, 0) << c.args;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << c.args << ": " << r.err;
        EXPECT_NE(r.err.find(c.expected), std::string::npos)
            << c.args << ": expected '" << c.expected << "' in: " << r.err;
        EXPECT_EQ(dir.count(), 1) << c.args << ": a file was written";
    }
    // A keyframe error names the file and the JSON path.
    const std::string bad = dir.write("bad.json", R"({"objects": [{"type": "sphere",
        "radius": {"keyframes": [{"time": 1, "value": 1}, {"time": 0, "value": 2}]}}]})");
    RunResult r = runCli("render " + bad + " -q --time 0:1" + pattern, dir);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("bad.json: /objects/0/radius/keyframes/1/time: time 0 is not after"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(dir.count(), 2);
}

}  // namespace
}  // namespace sdft::e2e
