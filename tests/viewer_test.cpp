// sdftrace view end to end: a script drives the window under Xvfb (Mesa's software OpenGL), and
// its screenshots must be the CLI's render of the command it prints. Skipped with a message where
// the build has no viewer or no X server can be started.
#include <gtest/gtest.h>

#include <cstdlib>
#include <sstream>

#include "cli_runner.h"

namespace sdft::e2e {
namespace {

const std::string kSource = SDFT_SOURCE_DIR;

bool haveXvfb() { return std::system("command -v xvfb-run >/dev/null 2>&1") == 0; }

// Leak detection off for the viewer's process: Mesa and X keep allocations to the end.
const std::string kXvfb =
    "ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 xvfb-run -a -s '-screen 0 1280x1024x24' ";

#ifdef SDFT_HAVE_VIEWER
constexpr bool kViewer = true;
#else
constexpr bool kViewer = false;
#endif

// Runs the command line `sdftrace render ...` the viewer printed, writing its colour to `color`
// and its AOV (if the line names one) to `aov`.
RunResult runPrintedCommand(const std::string& line, const std::string& color,
                            const std::string& aov, const TempDir& dir) {
    std::istringstream words(line);
    std::string w, args;
    words >> w >> w;  // "sdftrace render"
    while (words >> w) {
        if (w == "-o") {
            words >> w;
            w = color;
            args += " -o";
        } else if (w == "--aov") {
            words >> w;
            w = w.substr(0, w.find('=') + 1) + aov;
            args += " --aov";
        }
        args += " " + w;
    }
    return runCli("render -q" + args, dir);
}

float maxDifference(const std::string& a, const std::string& b) {
    int w1 = 0, h1 = 0, c1 = 0, w2 = 0, h2 = 0, c2 = 0;
    const auto x = readPfm(a, w1, h1, c1), y = readPfm(b, w2, h2, c2);
    if (x.empty() || x.size() != y.size() || w1 != w2 || h1 != h2) return 1e30f;
    float d = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        if (std::isinf(x[i]) && std::isinf(y[i])) continue;
        d = std::max(d, std::fabs(x[i] - y[i]));
    }
    return d;
}

TEST(Viewer, AScriptedViewIsTheRenderOfTheCommandItPrints) {
    if (!kViewer) GTEST_SKIP() << "this build has no viewer (GLFW, OpenGL or Dear ImGui missing)";
    if (!haveXvfb()) GTEST_SKIP() << "xvfb-run not found (Debian's xvfb): no display to test on";
    TempDir dir;
    const std::string script = dir.write("s.txt",
                                         "orbit 80 -30   # a left drag\n"
                                         "zoom 1.5\n"
                                         "pan 12 -6\n"
                                         "fly 0.2 0 0.1\n"
                                         "set shadow_method soft\n"
                                         "set ao true\n"
                                         "tracer classic\n"
                                         "set omega 1.4\n"
                                         "frames 3\n"
                                         "aov steps\n"
                                         "wait\n"
                                         "command\n"
                                         "screenshot " +
                                             dir.file("steps.pfm") +
                                             "\n"
                                             "aov color\n"
                                             "screenshot " +
                                             dir.file("color.pfm") +
                                             "\n"
                                             "quit\n");
    const RunResult r = runCli("view " + kSource +
                                   "/examples/shadows.json --width 120 --height "
                                   "80 --script " +
                                   script,
                               dir, kXvfb);
    if (r.status != 0 && r.err.find("xvfb-run") != std::string::npos)
        GTEST_SKIP() << "Xvfb could not start: " << r.err;
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string line = r.out.substr(0, r.out.find('\n'));
    ASSERT_EQ(line.rfind("sdftrace render ", 0), 0u) << r.out;
    EXPECT_NE(line.find("--classic"), std::string::npos) << line;
    EXPECT_NE(line.find("--shadow-method soft"), std::string::npos) << line;
    EXPECT_NE(line.find("--ao"), std::string::npos) << line;
    const RunResult cli =
        runPrintedCommand(line, dir.file("cli.pfm"), dir.file("cli_steps.pfm"), dir);
    ASSERT_EQ(cli.status, 0) << cli.err << "\n" << line;
    // The same code path, camera and settings: equal to float rounding of the printed camera.
    EXPECT_LT(maxDifference(dir.file("color.pfm"), dir.file("cli.pfm")), 1e-5f) << line;
    EXPECT_LT(maxDifference(dir.file("steps.pfm"), dir.file("cli_steps.pfm")), 1e-5f) << line;
}

TEST(Viewer, AFailingScriptCommandIsOneErrorAndAnExitStatus) {
    if (!kViewer) GTEST_SKIP() << "this build has no viewer";
    if (!haveXvfb()) GTEST_SKIP() << "xvfb-run not found";
    TempDir dir;
    const std::string script =
        dir.write("s.txt", "wait\nscreenshot " + dir.file("no/such/dir/x.png") + "\nquit\n");
    const RunResult r =
        runCli("view --width 64 --height 48 --frames 1 --script " + script, dir, kXvfb);
    if (r.status != 0 && r.err.find("xvfb-run") != std::string::npos)
        GTEST_SKIP() << "Xvfb could not start: " << r.err;
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("screenshot"), std::string::npos) << r.err;
}

TEST(Viewer, ABadScriptOrInputFailsBeforeAnyWindow) {
    TempDir dir;
    const std::string script = dir.write("bad.txt", "orbit 1 2\nspin 3\n");
    RunResult r = runCli("view --script " + script, dir, "env -u DISPLAY ");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("bad.txt:2: unknown command 'spin'"), std::string::npos) << r.err;
    r = runCli("view " + dir.file("missing.json"), dir, "env -u DISPLAY ");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("missing.json"), std::string::npos) << r.err;
    r = runCli("view", dir, "env -u DISPLAY -u WAYLAND_DISPLAY ");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find(kViewer ? "needs a display" : "has no viewer"), std::string::npos)
        << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;  // one line
}

}  // namespace
}  // namespace sdft::e2e
