// Every kind of bad input through the CLI: a non-zero exit, one clear line naming the file and the
// JSON path (or the flag), what was wrong and what is accepted, and no output file left behind.
#include <gtest/gtest.h>

#include <cmath>

#include "cli_runner.h"

namespace sdft::e2e {
namespace {

const char* kGoodScene = R"({
  "camera": {"eye": [0, 1, 4], "target": [0, 0, 0], "width": 32, "height": 24},
  "lights": [{"type": "directional", "direction": [-1, -1, -1]}],
  "objects": [{"type": "sphere", "radius": 1}]
})";

std::string sceneWithObject(const std::string& object) {
    return R"({"camera": {"width": 16, "height": 12}, "objects": [)" + object + "]}";
}

struct BadCase {
    const char* name;
    std::string scene;                  // written to bad.json (empty: none)
    std::string args;                   // after "render"
    std::vector<std::string> expected;  // fragments of the error line
};

// Names the case in test listings instead of dumping its bytes.
void PrintTo(const BadCase& c, std::ostream* os) { *os << c.name; }

class BadInput : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadInput, FailsWithOneClearLineAndNoOutput) {
    const BadCase& c = GetParam();
    TempDir dir;
    std::string args = c.args;
    if (!c.scene.empty()) args = dir.write("bad.json", c.scene) + " " + args;
    std::string out = dir.file("out.png");
    RunResult r = runCli("render " + args + " -o " + out + " -q", dir);
    EXPECT_NE(r.status, 0) << c.name;
    // One line, on stderr.
    ASSERT_FALSE(r.err.empty()) << c.name;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << c.name << ": " << r.err;
    for (const std::string& fragment : c.expected) {
        EXPECT_NE(r.err.find(fragment), std::string::npos)
            << c.name << ": expected '" << fragment << "' in: " << r.err;
    }
    EXPECT_FALSE(std::filesystem::exists(out)) << c.name;
    EXPECT_EQ(dir.count(), c.scene.empty() ? 0 : 1) << c.name << ": a stray file was left behind";
}

INSTANTIATE_TEST_SUITE_P(
    Cli, BadInput,
    ::testing::Values(
        BadCase{"film_over_memory_budget",
                "",
                "--width 4000 --height 3000 --max-memory 64M",
                {"--width/--height: needs", "(the film of a 4000x3000 image with its AOVs)",
                 "more than the memory budget of 64 MiB (--max-memory)"}},
        BadCase{"shadow_map_over_memory_budget",
                R"({"camera": {"width": 16, "height": 12},
                    "lights": [{"type": "point", "position": [0, 4, 0]}],
                    "objects": [{"type": "sphere", "radius": 1}],
                    "render": {"shadow_method": "evsm", "shadow_map_resolution": 8192}})",
                "--max-memory 256M",
                {"shadow_map_resolution 8192: needs", "more than the memory budget of 256 MiB"}},
        BadCase{
            "max_memory_not_a_size", "", "--max-memory 2X", {"--max-memory: 2X: expected a size"}},
        BadCase{"temporal_history_over_memory_budget",
                "",
                "--frames 4 --max-memory 24M",
                {"--frames: needs 25 MiB (temporal accumulation of 800x450 frames",
                 "more than the memory budget of 24 MiB (--max-memory)"}},
        BadCase{"malformed_json",
                "{\"objects\": [ {\"type\": \"sphere\", }",
                "",
                {"bad.json", "malformed JSON", "line 1"}},
        BadCase{
            "unknown_type",
            sceneWithObject(R"({"type": "spheer", "radius": 1})"),
            "",
            {"bad.json", "/objects/0/type", "unknown object type 'spheer'", "accepted:", "sphere"}},
        BadCase{"unknown_operator_child",
                sceneWithObject(R"({"type": "union", "children": [{"type": "blend"}]})"),
                "",
                {"/objects/0/children/0/type", "unknown object type 'blend'"}},
        BadCase{"missing_field",
                sceneWithObject(R"({"type": "sphere"})"),
                "",
                {"/objects/0", "missing required key 'radius'"}},
        BadCase{"wrong_type",
                sceneWithObject(R"({"type": "sphere", "radius": "big"})"),
                "",
                {"/objects/0/radius", "expected a positive radius, got a string"}},
        BadCase{"negative_radius",
                sceneWithObject(R"({"type": "sphere", "radius": -1})"),
                "",
                {"/objects/0/radius", "expected a positive radius, got -1"}},
        BadCase{"non_finite",
                sceneWithObject(R"({"type": "sphere", "radius": 1e999})"),
                "",
                {"bad.json", "number overflow parsing '1e999'", "finite"}},
        BadCase{"vector_length",
                sceneWithObject(R"({"type": "box", "size": [1, 2]})"),
                "",
                {"/objects/0/size", "array of 3 numbers"}},
        BadCase{"unknown_key",
                sceneWithObject(R"({"type": "sphere", "radius": 1, "raduis": 2})"),
                "",
                {"/objects/0/raduis", "unknown key"}},
        BadCase{"unknown_material",
                sceneWithObject(R"({"type": "sphere", "radius": 1, "material": "gold"})"),
                "",
                {"/objects/0/material", "unknown material 'gold'"}},
        BadCase{"fov_out_of_range",
                R"({"camera": {"fov": 180}, "objects": [{"type": "sphere", "radius": 1}]})",
                "",
                {"/camera/fov", "(0, 180)"}},
        BadCase{"zero_image",
                R"({"camera": {"width": 0}, "objects": [{"type": "sphere", "radius": 1}]})",
                "",
                {"/camera/width", "[1, 65536]"}},
        BadCase{"no_objects", R"({"objects": []})", "", {"/objects", "at least one object"}},
        BadCase{"nesting_too_deep",
                [] {
                    std::string s = R"({"objects": [)";
                    for (int i = 0; i < 300; ++i) s += R"({"type": "union", "children": [)";
                    s += R"({"type": "sphere", "radius": 1})";
                    for (int i = 0; i < 300; ++i) s += "]}";
                    return s + "]}";
                }(),
                "",
                {"bad.json", "/objects/0/children/0/", "nest deeper than 256 levels"}},
        BadCase{"number_beyond_float_range",
                sceneWithObject(R"({"type": "sphere", "radius": 1e20})"),
                "",
                {"/objects/0/radius", "got 1e+20", "within +-1e9"}},
        BadCase{"objects_too_small",
                sceneWithObject(R"({"type": "sphere", "radius": 1e-8})"),
                "",
                {"/objects", "span only 2e-08", "at least 1e-6"}},
        BadCase{"eye_beyond_float_range", "", "--eye 1e20,0,0", {"--eye", "within +-1e9"}},
        BadCase{"flag_beyond_float_range", "", "--max-distance 1e12", {"--max-distance", "1e9"}},
        BadCase{
            "repeat_overlap",
            sceneWithObject(
                R"({"type": "repeat", "cell": [1, 1, 1], "count": [1, 1, 1], "child": {"type": "sphere", "radius": 0.8}})"),
            "",
            {"/objects/0/cell", "twice"}},
        BadCase{"omega",
                R"({"render": {"omega": 2.5}, "objects": [{"type": "sphere", "radius": 1}]})",
                "",
                {"/render/omega", "[1, 2)"}},
        BadCase{"absurd_size", "", "--width 65536 --height 65536", {"--width/--height", "GiB"}},
        BadCase{"missing_scene",
                "",
                "/nonexistent/scene.json",
                {"/nonexistent/scene.json", "cannot open"}},
        BadCase{"unknown_flag", "", "--frobnicate", {"--frobnicate", "--help"}},
        BadCase{"bad_fov_flag", "", "--fov 0", {"--fov"}},
        BadCase{"bad_eye_flag", "", "--eye 1,2", {"--eye", "x,y,z"}},
        BadCase{"bad_aov_name",
                "",
                "--aov depht=/tmp/x.exr",
                {"--aov depht=/tmp/x.exr", "color, depth"}},
        BadCase{
            "bad_aov_extension", "", "--aov depth=/tmp/x.jpg", {"--aov depth", ".png, .exr, .pfm"}},
        BadCase{"zero_size_sphere_light",
                R"({"lights": [{"type": "sphere", "position": [0, 3, 0], "radius": 0}],
                    "objects": [{"type": "sphere", "radius": 1}]})",
                "",
                {"bad.json", "/lights/0/radius", "positive radius"}},
        BadCase{"degenerate_rect_light",
                R"({"lights": [{"type": "rect", "position": [0, 3, 0], "u": [1, 0, 0],
                                "v": [2, 0, 0]}], "objects": [{"type": "sphere", "radius": 1}]})",
                "",
                {"bad.json", "/lights/0/v", "non-zero area"}},
        BadCase{"sun_angle_out_of_range",
                R"({"lights": [{"type": "directional", "direction": [0, -1, 0], "angle": 90}],
                    "objects": [{"type": "sphere", "radius": 1}]})",
                "",
                {"bad.json", "/lights/0/angle", "[0, 90)"}},
        BadCase{"unknown_shadow_method",
                R"({"objects": [{"type": "sphere", "radius": 1}],
                    "render": {"shadow_method": "raytraced"}})",
                "",
                {"bad.json", "/render/shadow_method", "hard, soft, distributed, pcf, evsm"}},
        BadCase{"shadow_method_flag", "", "--shadow-method magic", {"--shadow-method", "magic"}},
        BadCase{"negative_ior",
                R"({"materials": {"glass": {"type": "dielectric", "ior": -1.5}},
                    "objects": [{"type": "sphere", "radius": 1, "material": "glass"}]})",
                "",
                {"bad.json", "/materials/glass/ior", "[1, 10]"}},
        BadCase{"unknown_material_type",
                R"({"materials": {"m": {"type": "velvet"}},
                    "objects": [{"type": "sphere", "radius": 1, "material": "m"}]})",
                "",
                {"bad.json", "/materials/m/type", "plastic, mirror, dielectric"}},
        BadCase{"unknown_secondary_epsilon",
                R"({"objects": [{"type": "sphere", "radius": 1}],
                    "render": {"secondary_epsilon": "adaptive"}})",
                "",
                {"bad.json", "/render/secondary_epsilon", "dynamic, global"}},
        BadCase{"missing_texture_file",
                R"({"materials": {"m": {"color": {"type": "image", "file": "nowhere.png"}}},
                    "objects": [{"type": "sphere", "radius": 1, "material": "m"}]})",
                "",
                {"bad.json", "/materials/m/color/file", "nowhere.png", "no such file"}},
        BadCase{"unreadable_image",
                R"({"textures": {"t": {"type": "image", "file": ")" + std::string(SDFT_SOURCE_DIR) +
                    R"(/README.md"}},
                    "materials": {"m": {"color": "t"}},
                    "objects": [{"type": "sphere", "radius": 1, "material": "m"}]})",
                "",
                {"bad.json", "/textures/t/file", "README.md", "unreadable image", "PNG"}},
        BadCase{"unknown_texture_type",
                R"({"materials": {"m": {"color": {"type": "plaid"}}},
                    "objects": [{"type": "sphere", "radius": 1, "material": "m"}]})",
                "",
                {"bad.json", "/materials/m/color/type", "checker, noise, turbulence, marble"}},
        BadCase{"unknown_texture_name",
                R"({"materials": {"m": {"color": "granite"}},
                    "objects": [{"type": "sphere", "radius": 1, "material": "m"}]})",
                "",
                {"bad.json", "/materials/m/color", "granite", "/textures"}},
        BadCase{"solid_image_texture",
                R"({"materials": {"m": {"color": {"type": "image", "file": "x.png",
                                                   "projection": "solid"}}},
                    "objects": [{"type": "sphere", "radius": 1, "material": "m"}]})",
                "",
                {"bad.json", "/materials/m/color/projection", "planar, triplanar, grid"}},
        BadCase{"texture_gain_out_of_range",
                R"({"materials": {"m": {"color": {"type": "noise", "gain": 1.5}}},
                    "objects": [{"type": "sphere", "radius": 1, "material": "m"}]})",
                "",
                {"bad.json", "/materials/m/color/gain", "(0, 1)"}},
        BadCase{"bake_unbounded_child",
                R"({"objects": [{"type": "bake", "texcoords": "sphere",
                                 "child": {"type": "plane", "normal": [0, 1, 0]}}]})",
                "",
                {"bad.json", "/objects/0/child", "unbounded"}},
        BadCase{"bake_unknown_helper",
                R"({"objects": [{"type": "bake", "texcoords": "torus",
                                 "child": {"type": "sphere", "radius": 1}}]})",
                "",
                {"bad.json", "/objects/0/texcoords", "sphere, cylinder"}},
        BadCase{"unknown_integrator",
                R"({"objects": [{"type": "sphere", "radius": 1}],
                    "render": {"integrator": "bidirectional"}})",
                "",
                {"bad.json", "/render/integrator", "direct, path"}},
        BadCase{"zero_spp",
                R"({"objects": [{"type": "sphere", "radius": 1}],
                    "render": {"integrator": "path", "spp": 0}})",
                "",
                {"bad.json", "/render/spp"}},
        BadCase{"roughness_out_of_range",
                R"({"materials": {"m": {"roughness": 1.5}},
                    "objects": [{"type": "sphere", "radius": 1, "material": "m"}]})",
                "",
                {"bad.json", "/materials/m/roughness", "[0, 1]"}},
        BadCase{"negative_environment",
                R"({"environment": [0.5, -1, 0.5], "objects": [{"type": "sphere", "radius": 1}]})",
                "",
                {"bad.json", "/environment", "non-negative"}},
        BadCase{"integrator_flag", "", "--integrator photon", {"--integrator", "photon"}},
        BadCase{"max_depth_flag", "", "--integrator path --max-depth 0", {"--max-depth"}},
        BadCase{"frame_pattern_without_number",
                "",
                "--frames 2 --frame-pattern frames.png",
                {"--frame-pattern frames.png", "%04d"}},
        BadCase{"taa_alpha_out_of_range", "", "--frames 2 --taa-alpha 1", {"--taa-alpha"}},
        BadCase{"shadow_map_resolution",
                R"({"objects": [{"type": "sphere", "radius": 1}],
                    "render": {"shadow_method": "pcf", "shadow_map_resolution": 4}})",
                "",
                {"bad.json", "/render/shadow_map_resolution", "16"}}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return std::string(info.param.name); });

TEST(Cli, UnwritableOutputPathFailsBeforeRendering) {
    TempDir dir;
    RunResult r = runCli("render -q --width 8 --height 8 -o /nonexistent-dir/x.png", dir);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("--output /nonexistent-dir/x.png"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
}

TEST(Cli, UnwritableAovLeavesNoColorImageEither) {
    TempDir dir;
    std::string out = dir.file("out.png");
    RunResult r = runCli(
        "render -q --width 8 --height 8 -o " + out + " --aov depth=/nonexistent-dir/d.exr", dir);
    EXPECT_NE(r.status, 0);
    EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(Cli, HelpDocumentsEveryFlag) {
    TempDir dir;
    RunResult r = runCli("render --help", dir);
    EXPECT_EQ(r.status, 0);
    for (const char* flag :
         {"--output",       "--aov",       "--eye",           "--target",      "--up",
          "--fov",          "--width",     "--height",        "--threads",     "--omega",
          "--screen-space", "--force-hit", "--discontinuity", "--fixed-steps", "--hybrid",
          "--max-steps",    "--tau",       "--normals",       "--classic",     "--integrator",
          "--spp",          "--max-depth"}) {
        EXPECT_NE(r.out.find(flag), std::string::npos) << flag;
    }
}

TEST(Cli, RendersASceneFileWithEveryAovFormat) {
    TempDir dir;
    std::string scene = dir.write("scene.json", kGoodScene);
    RunResult r = runCli(
        "render " + scene + " -o " + dir.file("c.png") + " --aov depth=" + dir.file("d.exr") +
            " --aov depth=" + dir.file("d.pfm") + " --aov steps=" + dir.file("s.png") +
            " --aov normal=" + dir.file("n.exr") + " --aov error=" + dir.file("e.pfm") +
            " --aov color=" + dir.file("c.exr") + " --threads 2",
        dir);
    ASSERT_EQ(r.status, 0) << r.err;
    for (const char* f : {"c.png", "d.exr", "d.pfm", "s.png", "n.exr", "e.pfm", "c.exr"}) {
        EXPECT_TRUE(std::filesystem::exists(dir.file(f))) << f;
    }
    // The PFM depth: 32x24 single channel, header then floats; misses are +inf, hits near 3.
    std::string pfm = readFile(dir.file("d.pfm"));
    ASSERT_EQ(pfm.substr(0, 3), "Pf\n");
    EXPECT_EQ(pfm.size(), std::string("Pf\n32 24\n-1.0\n").size() + 32 * 24 * 4);
    // The summary line: time, rays/s, evaluations per ray, thread count.
    EXPECT_NE(r.err.find("on 2 threads"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("Mrays/s"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("evaluations per primary ray"), std::string::npos) << r.err;
    EXPECT_EQ(dir.count(), 8);  // the scene and seven images, no temporaries
}

TEST(Cli, RendersTheBuiltInDemoWithoutASceneArgument) {
    TempDir dir;
    RunResult r = runCli("render -q --width 64 --height 36 -o " + dir.file("demo.png"), dir);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(std::filesystem::exists(dir.file("demo.png")));
}

TEST(Cli, EveryExampleSceneParsesAndRenders) {
    TempDir dir;
    int n = 0;
    for (auto& e :
         std::filesystem::directory_iterator(std::string(SDFT_SOURCE_DIR) + "/examples")) {
        if (e.path().extension() != ".json") continue;
        RunResult r = runCli(
            "render -q --width 48 --height 32 " + e.path().string() + " -o " + dir.file("x.pfm"),
            dir);
        ASSERT_EQ(r.status, 0) << e.path() << ": " << r.err;
        int w, h, ch;
        std::vector<float> color = readPfm(dir.file("x.pfm"), w, h, ch);
        ASSERT_EQ(color.size(), 48u * 32u * 3u);
        for (float v : color) ASSERT_TRUE(std::isfinite(v)) << e.path() << ": a non-finite pixel";
        ++n;
    }
    EXPECT_GE(n, 4);
}

}  // namespace
}  // namespace sdft::e2e
