// sdftrace mesh: fields back to meshes from grid files, scene files and meshes, and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "cli_runner.h"

namespace sdft::e2e {
namespace {

std::string dataMesh(const std::string& name) {
    return std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + name;
}

// "N vertices, M triangles" from the summary line.
bool counts(const std::string& err, long& vertices, long& triangles) {
    const size_t at = err.find("vertices, ");
    if (at == std::string::npos) return false;
    size_t start = err.rfind(' ', at - 2);
    return std::sscanf(err.c_str() + start + 1, "%ld vertices, %ld triangles", &vertices,
                       &triangles) == 2;
}

TEST(ExtractMeshCli, GridSceneAndMeshInputsGiveMeshesThatLoadBack) {
    TempDir dir;
    const std::string scene = dir.write(
        "s.json", R"({"objects": [{"type": "torus", "major_radius": 1, "minor_radius": 0.3}]})");
    ASSERT_EQ(runCli("bake " + scene + " --res 48 -o " + dir.file("t.vdb"), dir).status, 0);
    struct Case {
        std::string args, out;
    };
    for (const Case& c : {Case{dir.file("t.vdb"), "a.ply"}, Case{scene + " --res 40", "b.obj"},
                          Case{dir.file("t.vdb") + " --res 32 --adaptivity 0.5", "c.stl"},
                          Case{dataMesh("elephant-with-holes.obj") + " --res 40", "d.ply"}}) {
        RunResult r = runCli("mesh -q " + c.args + " -o " + dir.file(c.out), dir);
        ASSERT_EQ(r.status, 0) << c.args << "\n" << r.err;
        long v = 0, t = 0;
        ASSERT_TRUE(counts(r.err, v, t)) << r.err;
        EXPECT_GT(t, 500) << r.err;
        // The mesh is closed (even from the open elephant: its grid's surface is), and it bakes.
        RunResult back =
            runCli("bake " + dir.file(c.out) + " --res 24 -o " + dir.file(c.out + ".sdfg"), dir);
        ASSERT_EQ(back.status, 0) << back.err;
        EXPECT_NE(back.err.find(" 0 boundary edges"), std::string::npos) << c.out << back.err;
    }
}

TEST(ExtractMeshCli, BadInputIsOneLineAndNoFile) {
    TempDir dir;
    const std::string scene =
        dir.write("s.json", R"({"objects": [{"type": "sphere", "radius": 1}]})");
    const std::string plane =
        dir.write("p.json", R"({"objects": [{"type": "plane", "normal": [0, 1, 0]}]})");
    struct Case {
        std::string args, expect;
    };
    for (const Case& c : {
             Case{scene + " -o " + dir.file("x.off"), "accepted extensions: .ply"},
             Case{dir.file("missing.sdfg") + " -o " + dir.file("x.ply"), "missing.sdfg"},
             Case{scene + " --adaptivity 2 -o " + dir.file("x.ply"), "--adaptivity"},
             Case{scene + " --isovalue 5 -o " + dir.file("x.ply"), "--isovalue 5"},
             Case{scene + " --res 2 -o " + dir.file("x.ply"), "--res"},
             Case{plane + " -o " + dir.file("x.ply"), "unbounded"},
             Case{scene + " -o /nonexistent-dir/x.ply", "--output"},
         }) {
        RunResult r = runCli("mesh -q " + c.args, dir);
        EXPECT_NE(r.status, 0) << c.args;
        EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_FALSE(std::filesystem::exists(dir.file("x.ply")));
        EXPECT_FALSE(std::filesystem::exists(dir.file("x.off")));
    }
    EXPECT_EQ(dir.count(), 2);  // the two scene files: no output, no temporary
    RunResult help = runCli("mesh --help", dir);
    EXPECT_EQ(help.status, 0);
    EXPECT_NE(help.out.find("--adaptivity"), std::string::npos);
}

// OpenVDB's tools are a plugin (docs/decisions/0008-openvdb-as-a-plugin.md): the executable does
// not load libopenvdb; without the plugin, writing .vdb and meshing fail with one line naming it
// and leave no file, and everything else (reading and rendering .vdb) still works.
TEST(ExtractMeshCli, OpenVdbIsAPluginLoadedOnlyWhenNeeded) {
    TempDir dir;
    const std::string scene =
        dir.write("s.json", R"({"objects": [{"type": "sphere", "radius": 1}]})");
    ASSERT_EQ(runCli("bake " + scene + " --res 24 -o " + dir.file("s.vdb"), dir).status, 0);
    const std::string libs = librariesLoadedAtStart();
    EXPECT_NE(libs.find("libtbb"), std::string::npos) << libs;
    EXPECT_EQ(libs.find("libopenvdb"), std::string::npos) << libs;

    setenv("SDFT_PLUGIN_DIR", dir.file("no-plugins-here").c_str(), 1);
    for (const std::string& args : {"mesh -q " + scene + " -o " + dir.file("x.ply"),
                                    "bake " + scene + " --res 24 -o " + dir.file("x.vdb"),
                                    "convert " + dir.file("s.vdb") + " " + dir.file("x.vdb")}) {
        const RunResult r = runCli(args, dir);
        EXPECT_NE(r.status, 0) << args;
        EXPECT_NE(r.err.find("libsdftrace_openvdb.so not found"), std::string::npos) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    }
    const RunResult render = runCli(
        "render -q " + dir.file("s.vdb") + " --width 32 --height 24 -o " + dir.file("s.png"), dir);
    unsetenv("SDFT_PLUGIN_DIR");
    EXPECT_EQ(render.status, 0) << render.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("x.ply")));
    EXPECT_FALSE(std::filesystem::exists(dir.file("x.vdb")));
    EXPECT_EQ(dir.count(), 3);  // s.json, s.vdb, s.png: no output, no temporary
}

}  // namespace
}  // namespace sdft::e2e
