#include "sdftrace/view/viewer_session.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "sdftrace/core/error.h"
#include "sdftrace/io/image_io.h"
#include "sdftrace/render/temporal.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"
#include "sdftrace/scene/render_options.h"

namespace sdft {
namespace {

namespace fs = std::filesystem;

struct TempScene {
    fs::path dir = fs::temp_directory_path() / ("sdft_view_" + std::to_string(::getpid()));
    fs::path file = dir / "scene.json";
    TempScene() { fs::create_directories(dir); }
    ~TempScene() { fs::remove_all(dir); }
    void write(const std::string& text) {
        std::ofstream(file, std::ios::binary) << text;
        // A new time stamp even within the file system's granularity.
        static int bump = 0;
        fs::last_write_time(file, fs::file_time_type::clock::now() + std::chrono::seconds(++bump));
    }
};

const char* kSphere =
    R"({"camera": {"eye": [0, 0, 4], "target": [0, 0, 0], "width": 40, "height": 30},
  "objects": [{"type": "sphere", "radius": 1.0}]})";
const char* kBigSphere =
    R"({"camera": {"eye": [0, 0, 4], "target": [0, 0, 0], "width": 40, "height": 30},
  "objects": [{"type": "sphere", "radius": 1.5}]})";

void refine(ViewerSession& s) {
    while (s.step()) {
    }
}

TEST(ViewerSession, TheRefinedViewIsTheRenderOfItsCommand) {
    ViewerOptions o;
    o.width = 64;
    o.height = 36;
    o.progressive.frames = 3;
    ViewerSession s(o);  // the demo
    bool quit = false;
    std::string out;
    for (const ViewCommand& c :
         parseViewScript("orbit 60 -20\nzoom 1\npan 5 3\nset shadow_method soft\nset omega 1.5\n"
                         "tracer classic\nset screen_space false\ncommand\n",
                         "script")) {
        ASSERT_TRUE(s.run(c, quit, out));
    }
    refine(s);
    EXPECT_TRUE(s.refined());
    EXPECT_NE(out.find("--classic"), std::string::npos) << out;
    EXPECT_NE(out.find("--shadow-method soft"), std::string::npos) << out;
    EXPECT_NE(out.find("--omega 1.5"), std::string::npos) << out;
    EXPECT_NE(out.find("--no-screen-space"), std::string::npos) << out;
    EXPECT_NE(out.find("--frames 3"), std::string::npos) << out;
    // What those flags render (as render_command.cpp applies them).
    Scene scene = demoScene();
    scene.camera = s.camera();
    scene.settings.trace = TraceOptions::classic();
    findRenderOption("shadow_method")->set(scene.settings, 1);
    findRenderOption("omega")->set(scene.settings, 1.5);
    findRenderOption("screen_space")->set(scene.settings, 0);
    const RenderPlan plan = planRender(scene);
    Film reference(64, 36);
    renderFrames(plan, reference, TemporalOptions{.frames = 3});
    int w = 0, h = 0;
    float range[2];
    EXPECT_EQ(s.picture(w, h, range), toneMapSrgb(reference.color));
    EXPECT_EQ(w, 64);
    EXPECT_EQ(h, 36);
}

TEST(ViewerSession, WaitHoldsUntilRefinedAndQuitQuits) {
    ViewerOptions o;
    o.width = 32;
    o.height = 24;
    o.progressive.frames = 2;
    ViewerSession s(o);
    bool quit = false;
    std::string out;
    const auto cmds = parseViewScript("wait\nquit\n", "script");
    EXPECT_FALSE(s.run(cmds[0], quit, out));
    refine(s);
    EXPECT_TRUE(s.run(cmds[0], quit, out));
    EXPECT_TRUE(s.run(cmds[1], quit, out));
    EXPECT_TRUE(quit);
}

TEST(ViewerSession, AnEditedFileReloadsAndABrokenOneKeepsTheLastGoodView) {
    TempScene t;
    t.write(kSphere);
    ViewerOptions o;
    o.input = t.file.string();
    o.progressive.frames = 1;
    ViewerSession s(o);
    s.setOption("omega", 1.1);  // a switch set in the panel outlives reloads
    refine(s);
    int w, h;
    float range[2];
    s.setAov(Aov::Depth);
    const auto before = s.picture(w, h, range);
    const float nearBefore = range[0];
    EXPECT_FALSE(s.pollInput());  // nothing changed
    t.write(kBigSphere);
    EXPECT_TRUE(s.pollInput());
    EXPECT_TRUE(s.error().empty());
    EXPECT_EQ(s.loads(), 2);
    EXPECT_FLOAT_EQ(s.settings().trace.omega, 1.1f);
    refine(s);
    (void)s.picture(w, h, range);
    EXPECT_NEAR(range[0], nearBefore - 0.5f, 0.02f);  // the bigger sphere is nearer
    t.write(R"({"objects": [{"type": "sphere", "radius": -2}]})");
    EXPECT_TRUE(s.pollInput());
    EXPECT_NE(s.error().find("/objects/0/radius"), std::string::npos) << s.error();
    EXPECT_FALSE(s.step());  // nothing new to render: the last good picture stays
    (void)s.picture(w, h, range);
    EXPECT_NEAR(range[0], nearBefore - 0.5f, 0.02f);
    t.write(kSphere);
    EXPECT_TRUE(s.pollInput());
    EXPECT_TRUE(s.error().empty());
    refine(s);
    EXPECT_EQ(s.picture(w, h, range), before);
}

// A scene's mesh goes through the same readers as `bake` and Python: a damaged mesh file is the
// one line that names the scene, the object and the mesh file (and its line, for text formats),
// and the last good view stays.
TEST(ViewerSession, ADamagedMeshIsOneLineAndTheLastGoodViewStays) {
    TempScene t;
    const fs::path obj = t.dir / "tetra.obj", ply = t.dir / "tetra.ply";
    const std::string tetra =
        "v 1 1 1\nv -1 -1 1\nv -1 1 -1\nv 1 -1 -1\nf 1 2 3\nf 1 4 2\nf 1 3 4\nf 2 4 3\n";
    std::ofstream(obj, std::ios::binary) << tetra;
    auto sceneWith = [&](const fs::path& mesh) {
        return R"({"camera": {"eye": [0, 0, 4], "target": [0, 0, 0], "width": 40, "height": 30},
  "objects": [{"mesh": ")" +
               mesh.string() + R"(", "resolution": 16, "method": "exact"}]})";
    };
    t.write(sceneWith(obj));
    ViewerOptions o;
    o.input = t.file.string();
    o.progressive.frames = 1;
    ViewerSession s(o);
    ASSERT_TRUE(s.error().empty()) << s.error();
    refine(s);
    int w, h;
    float range[2];
    const auto before = s.picture(w, h, range);
    struct Damage {
        fs::path file;
        std::string bytes, expected;
    } damages[] = {
        {obj, tetra.substr(0, tetra.size() - 4) + "9\n",
         obj.string() + ":8: OBJ: a face uses vertex 9"},
        {obj, tetra + "f 1 2 x\n", obj.string() + ":9: OBJ: a face corner 'x'"},
        {ply,
         "ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\n"
         "property float y\nproperty float z\nelement face 2000\n"
         "property list uchar int vertex_indices\nend_header\n\x01\x02",
         ply.string() + ": PLY: "},
    };
    for (const Damage& d : damages) {
        std::ofstream(d.file, std::ios::binary) << d.bytes;
        t.write(sceneWith(d.file));
        EXPECT_TRUE(s.pollInput());
        // The scene file and the JSON path of the object, then the mesh reader's line.
        EXPECT_EQ(s.error().find(t.file.string() + ": /objects/0/mesh: " + d.expected), 0u)
            << s.error();
        EXPECT_EQ(s.error().find('\n'), std::string::npos) << s.error();
        EXPECT_FALSE(s.step());
        EXPECT_EQ(s.picture(w, h, range), before);
    }
}

TEST(ViewerSession, ScreenshotsAreTheAovAsRenderWritesIt) {
    TempScene t;
    ViewerOptions o;
    o.width = 24;
    o.height = 16;
    o.progressive.frames = 1;
    ViewerSession s(o);
    refine(s);
    s.setAov(Aov::Steps);
    s.screenshot((t.dir / "steps.pfm").string());
    EXPECT_TRUE(fs::exists(t.dir / "steps.pfm"));
    EXPECT_THROW(s.screenshot((t.dir / "x.bmp").string()), InputError);
    EXPECT_THROW(s.screenshot((t.dir / "no" / "x.png").string()), InputError);
    ViewerOptions missing;
    missing.input = (t.dir / "none.json").string();
    EXPECT_THROW(ViewerSession{missing}, InputError);
}

}  // namespace
}  // namespace sdft
