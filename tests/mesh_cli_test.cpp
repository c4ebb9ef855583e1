// Meshes through the CLI: bake, render directly, and bad mesh input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "cli_runner.h"

namespace sdft::e2e {
namespace {

std::string mesh(const std::string& name) {
    return std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + name;
}

TEST(MeshCli, BakesAClosedMeshExactlyAndRendersIt) {
    TempDir dir;
    RunResult bake =
        runCli("bake " + mesh("bunny_npm.obj") + " --res 48 -o " + dir.file("b.sdfg"), dir);
    ASSERT_EQ(bake.status, 0) << bake.err;
    EXPECT_NE(bake.err.find("0 boundary edges"), std::string::npos)
        << bake.err;  // the cleaning report
    for (const char* f : {"exact, 48x", "distances", "signs", "peak memory", "total"})
        EXPECT_NE(bake.err.find(f), std::string::npos) << f << "\n" << bake.err;
    RunResult info = runCli("info " + dir.file("b.sdfg"), dir);
    ASSERT_EQ(info.status, 0);
    EXPECT_EQ(info.out.find("0 inside"), std::string::npos)
        << info.out;  // a closed mesh has an inside
    RunResult render = runCli(
        "render -q --width 48 --height 36 " + mesh("bunny_npm.obj") + " -o " + dir.file("r.png"),
        dir);
    ASSERT_EQ(render.status, 0) << render.err;
    EXPECT_TRUE(std::filesystem::exists(dir.file("r.png")));
}

TEST(MeshCli, JumpFloodingWithVerifyReportsItsErrorAgainstExact) {
    TempDir dir;
    RunResult r =
        runCli("bake " + mesh("bunny_npm.obj") +
                   " --res 40 --method jfa --jfa-variant jfa+2 --verify -o " + dir.file("j.sdfg"),
               dir);
    ASSERT_EQ(r.status, 0) << r.err;
    for (const char* f : {"jump flooding", "verify jfa, stored samples", "verify jfa, narrow band",
                          "wrong sign", "8 passes (offset: time) 32:"}) {
        EXPECT_NE(r.err.find(f), std::string::npos) << f << "\n" << r.err;
    }
    // The reported maximum error stays under the unit test's bound (0.6 voxel).
    size_t at = r.err.find("narrow band (");
    ASSERT_NE(at, std::string::npos);
    float mean, p99, max;
    int samples;
    ASSERT_EQ(std::sscanf(r.err.c_str() + at, "narrow band (%d samples): mean %f, p99 %f, max %f",
                          &samples, &mean, &p99, &max),
              4);
    EXPECT_GT(samples, 1000);
    EXPECT_LT(max, 0.6f);
}

// Issue 4: meshes as scene objects, baked on load, rendered like any grid with the rest of a scene.
TEST(MeshCli, MeshObjectsInSceneFilesAreBakedOnLoad) {
    TempDir dir;
    std::string scene =
        dir.write("scene.json", R"({
      "camera": {"eye": [0.3, 0.3, 0.5], "target": [0, 0.1, 0], "width": 64, "height": 48},
      "lights": [{"type": "directional", "direction": [-1, -1, -1]}],
      "materials": {"clay": {"color": [0.8, 0.5, 0.4]}},
      "objects": [{"mesh": ")" + mesh("bunny_npm.obj") +
                                    R"(", "resolution": 48, "method": "jfa", "sign": "flood",
                   "band": 4, "material": "clay"},
                  {"type": "plane", "normal": [0, 1, 0], "distance": 0.03}]})");
    RunResult r = runCli(
        "render -q " + scene + " -o " + dir.file("m.png") + " --aov depth=" + dir.file("d.pfm"),
        dir);
    ASSERT_EQ(r.status, 0) << r.err;
    // The same scene without the mesh: the pixels the bunny covers change depth.
    std::string floorOnly = dir.write("floor.json", R"({
      "camera": {"eye": [0.3, 0.3, 0.5], "target": [0, 0.1, 0], "width": 64, "height": 48},
      "objects": [{"type": "plane", "normal": [0, 1, 0], "distance": 0.03}]})");
    ASSERT_EQ(runCli("render -q " + floorOnly + " -o " + dir.file("f.png") +
                         " --aov depth=" + dir.file("f.pfm"),
                     dir)
                  .status,
              0);
    int w, h, ch;
    std::vector<float> depth = readPfm(dir.file("d.pfm"), w, h, ch),
                       floor = readPfm(dir.file("f.pfm"), w, h, ch);
    int covered = 0;
    for (size_t i = 0; i < depth.size(); ++i)
        covered += std::isfinite(depth[i]) && !(std::fabs(depth[i] - floor[i]) < 1e-3f);
    EXPECT_GT(covered, 200);
    struct Bad {
        std::string objects, path;
    } bads[] = {
        {R"({"mesh": "missing.obj"})", "/objects/0/mesh"},
        {R"({"mesh": ")" + mesh("bunny_npm.obj") + R"(", "sign": "flood"})", "/objects/0/sign"},
        {R"({"mesh": ")" + mesh("bunny_npm.obj") + R"(", "sign": "magic"})", "/objects/0/sign"},
        {R"({"mesh": ")" + mesh("bunny_npm.obj") + R"(", "band": 1})", "/objects/0/band"},
    };
    for (const Bad& c : bads) {
        std::string bad = dir.write("bad.json", R"({"objects": [)" + c.objects + "]}");
        RunResult b = runCli("render -q " + bad + " -o " + dir.file("x.png"), dir);
        EXPECT_NE(b.status, 0) << c.objects;
        EXPECT_EQ(std::count(b.err.begin(), b.err.end(), '\n'), 1) << b.err;
        EXPECT_NE(b.err.find(c.path), std::string::npos) << b.err;
        EXPECT_FALSE(std::filesystem::exists(dir.file("x.png")));
    }
}

// Every method through the CLI: the summary names its stages, and the grid it writes loads and
// renders.
TEST(MeshCli, EveryMethodBakesAndSummarizesItsStages) {
    TempDir dir;
    struct Case {
        std::string args, stage;
    } cases[] = {
        {"--method exact --dense", "closest point transform"},
        {"--method exact --dense --closest bvh", "distances and signs"},
        {"--method jfa --sign flood", "signs (flood fill)"},
        {"--method danielsson", "danielsson sweeps"},
        {"--method edt --sign parity", "separable edt"},
        {"--method rtsdf --rays 8 --mask 2", "rays"},
    };
    for (const Case& c : cases) {
        RunResult r = runCli(
            "bake " + mesh("teapot.obj") + " --res 32 " + c.args + " -o " + dir.file("t.sdfg"),
            dir);
        ASSERT_EQ(r.status, 0) << c.args << ": " << r.err;
        EXPECT_NE(r.err.find(c.stage), std::string::npos) << c.args << ": " << r.err;
        RunResult render = runCli(
            "render -q --width 32 --height 24 " + dir.file("t.sdfg") + " -o " + dir.file("t.png"),
            dir);
        EXPECT_EQ(render.status, 0) << c.args << ": " << render.err;
    }
}

// Damaged copies of the mesh-file fuzz targets' seeds (a cube in every variant of PLY, STL, OFF,
// OBJ, glTF and GLB: fuzz/corpus/mesh_*/seed-cube*), cut short and with bytes changed, through
// `sdftrace bake`: each bakes or ends by itself with one line naming the file and exit status 1,
// no signal and no output file.
TEST(MeshCli, DamagedMeshFilesEndInOneLineAndNoOutput) {
    TempDir dir;
    int failed = 0, runs = 0;
    uint32_t seed = 12345;
    auto next = [&seed] { return seed = seed * 1664525u + 1013904223u; };
    const std::string corpora = std::string(SDFT_SOURCE_DIR) + "/fuzz/corpus";
    for (const auto& family : std::filesystem::directory_iterator(corpora)) {
        if (family.path().filename().string().rfind("mesh_", 0) != 0) continue;
        for (const auto& f : std::filesystem::directory_iterator(family.path())) {
            const std::string name = f.path().filename().string();
            if (name.rfind("seed-cube", 0) != 0) continue;
            const std::string bytes = readFile(f.path().string());
            for (int k = 0; k < 6; ++k) {
                std::string b = bytes;
                if (k < 3) {
                    b.resize(next() % b.size());
                } else {
                    for (int c = 0; c < 3; ++c) b[next() % b.size()] = static_cast<char>(next());
                }
                const std::string path = dir.write(name.substr(5), b);  // without "seed-"
                const std::string out = dir.file("out.sdfg");
                std::filesystem::remove(out);  // a bake before this one's
                const RunResult r = runCli("bake " + path + " --res 8 -q -o " + out, dir);
                ++runs;
                if (r.status == 0) continue;
                ++failed;
                EXPECT_EQ(r.status, 1) << path << ": " << r.err;
                EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
                EXPECT_NE(r.err.find(path), std::string::npos) << r.err;
                EXPECT_FALSE(std::filesystem::exists(out)) << path;
            }
        }
    }
    EXPECT_GE(runs, 60);
    EXPECT_GT(failed, runs / 2);
}

TEST(MeshCli, BadMeshInputFailsClearly) {
    TempDir dir;
    std::string garbage = dir.write("garbage.stl", "not a mesh");
    std::string flat = dir.write("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    // A closed tetrahedron scaled and moved beyond what float distance computations keep.
    auto tetrahedron = [&](const std::string& name, double scale, double offset) {
        std::string text;
        const double v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
        for (const auto& p : v) {
            char line[96];
            std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", offset + scale * p[0],
                          scale * p[1], scale * p[2]);
            text += line;
        }
        return dir.write(name, text + "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    };
    std::string huge = tetrahedron("huge.obj", 1e37, 1e38);
    std::string far = tetrahedron("far.obj", 1, 1e6);
    std::string unit = tetrahedron("unit.obj", 1, 0);
    std::string tiny = tetrahedron("tiny.obj", 1e-12, 0);
    std::string scene = dir.write("s.json", R"({"objects": [{"type": "sphere", "radius": 1}]})");
    struct Case {
        std::string args, fragment;
    } cases[] = {
        {"bake " + garbage + " -o " + dir.file("x.sdfg"), "not ascii STL"},
        {"bake " + flat + " -o " + dir.file("x.sdfg"), "no (non-degenerate) triangles"},
        {"bake " + dir.file("missing.obj") + " -o " + dir.file("x.sdfg"), "cannot open"},
        {"bake " + mesh("bunny_npm.obj") + " --method sdfgen -o " + dir.file("x.sdfg"),
         "accepted: exact, jfa, danielsson, edt, rtsdf"},
        {"bake " + mesh("bunny_npm.obj") + " --sign flood -o " + dir.file("x.sdfg"),
         "--sign flood: method exact accepts winding or parity"},
        {"bake " + mesh("bunny_npm.obj") + " --method rtsdf --rays 0 -o " + dir.file("x.sdfg"),
         "--rays"},
        {"bake " + mesh("bunny_npm.obj") + " --method jfa --res 4096 -o " + dir.file("x.sdfg"),
         "--res 4096: needs"},
        {"bake " + mesh("bunny_npm.obj") + " --jfa-variant 3+jfa -o " + dir.file("x.sdfg"),
         "--jfa-variant"},
        {"bake " + mesh("bunny_npm.obj") + " --dense --closest octree -o " + dir.file("x.sdfg"),
         "--closest"},
        {"render -q " + garbage + " -o " + dir.file("x.png"), "not ascii STL"},
        // Coordinates float geometry cannot resolve are refused with the range that works.
        {"bake " + huge + " -o " + dir.file("x.sdfg"), "coordinates reach 1.1e+38"},
        {"render -q " + huge + " -o " + dir.file("x.png"), "|x| <= 1e+09"},
        {"bake " + far + " -o " + dir.file("x.sdfg"), "lies 1e+06 from the origin"},
        {"bake " + tiny + " -o " + dir.file("x.sdfg"), "spans only 1e-12"},
        // Flags that do nothing for the input are errors.
        {"bake " + scene + " --res 16 --sign parity -o " + dir.file("x.sdfg"),
         "--sign: applies to meshes only"},
        {"bake " + scene + " --res 16 --method jfa -o " + dir.file("x.sdfg"),
         "--method: applies to meshes only"},
        {"bake " + mesh("bunny_npm.obj") + " --bounds 0,0,0,1,1,1 -o " + dir.file("x.sdfg"),
         "--bounds: applies to scene files only"},
        {"bake " + mesh("bunny_npm.obj") + " --rays 8 -o " + dir.file("x.sdfg"),
         "--rays: applies to --method rtsdf only"},
        {"bake " + mesh("bunny_npm.obj") + " --beta 1 -o " + dir.file("x.sdfg"),
         "--beta: applies to --sign beta only"},
        {"bake " + mesh("bunny_npm.obj") + " --dense --band 4 -o " + dir.file("x.sdfg"),
         "--band: applies to sparse grids only"},
        {"bake " + mesh("bunny_npm.obj") + " --texcoord-axis 0,0,1 -o " + dir.file("x.sdfg"),
         "--texcoord-axis: needs --texcoords"},
        // Memory budgets: checked before anything is allocated, with the bytes needed.
        {"bake " + unit + " --dense --res 4096 -o " + dir.file("x.sdfg"),
         "--res 4096: needs 256.2 GiB (the bake's arrays), more than the memory budget"},
        {"bake " + mesh("bunny_npm.obj") + " --dense --res 256 --max-memory 16M -o " +
             dir.file("x.sdfg"),
         "more than the memory budget of 16 MiB (--max-memory)"},
        {"bake " + scene + " --dense --res 512 --max-memory 64M -o " + dir.file("x.sdfg"),
         "--res 512: needs 515 MiB"},
        {"bake " + scene + " --res 16 --max-memory lots -o " + dir.file("x.sdfg"),
         "--max-memory: lots: expected a size such as 8G"},
        {"render -q " + mesh("stanford-bunny.obj") + " --max-memory 1M -o " + dir.file("x.png"),
         "stanford-bunny.obj: reading it needs more memory than the budget of 1 MiB"},
    };
    for (const Case& c : cases) {
        RunResult r = runCli(c.args, dir);
        EXPECT_NE(r.status, 0) << c.args;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_NE(r.err.find(c.fragment), std::string::npos) << c.args << ": " << r.err;
        EXPECT_FALSE(std::filesystem::exists(dir.file("x.sdfg")));
        EXPECT_FALSE(std::filesystem::exists(dir.file("x.png")));
    }
}

}  // namespace
}  // namespace sdft::e2e
