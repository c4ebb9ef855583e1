// Faults while writing: a full file system (a small tmpfs), a file-size limit, an output directory
// that disappears during the work, and a kill in the middle of a write. In every case no partial
// file is left at the output path and the error says what happened.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "cli_runner.h"

namespace sdft::e2e {
namespace {

const char* kScene = R"({"objects": [{"type": "smooth_union", "k": 0.2, "children": [
  {"type": "torus", "major_radius": 0.8, "minor_radius": 0.25},
  {"type": "sphere", "radius": 0.5, "translate": [0, 0.4, 0]}]}],
  "lights": [{"type": "directional", "direction": [0.3, -1, -0.4]}]})";

// Runs a shell command line; stderr is captured.
RunResult runShell(const std::string& command, const TempDir& dir) {
    const std::string err = dir.path() + "/.stderr";
    const std::string cmd = "( " + command + " ) 2>" + err + " >/dev/null </dev/null";
    const int raw = std::system(cmd.c_str());
    RunResult r;
    r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    r.err = readFile(err);
    std::filesystem::remove(err);
    return r;
}

std::vector<std::string> filesIn(const std::string& dir) {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(dir))
        names.push_back(e.path().filename().string());
    return names;
}

std::string joined(const std::vector<std::string>& v) {
    std::string s;
    for (const std::string& x : v) s += x + " ";
    return s;
}

// A 256 KiB tmpfs in a private mount namespace (unshare -rm: no privileges needed where user
// namespaces are enabled); every output there runs out of space.
TEST(WriteFaults, FullFileSystemLeavesNothingAndSaysSo) {
    TempDir dir;
    const std::string scene = dir.write("scene.json", kScene);
    const std::string mnt = dir.file("small");
    std::filesystem::create_directory(mnt);
    if (runShell("unshare -rm sh -c 'mount -t tmpfs -o size=256k none " + mnt + "'", dir).status)
        GTEST_SKIP() << "cannot mount a tmpfs here (no user namespaces)";
    // Images from close up (the object fills the frame) on an 8 KiB file system, grids on 256 KiB.
    const std::string close = " -q --eye 0,0.3,1.4 --target 0,0.2,0 --width 640 --height 480 ";
    struct Case {
        std::string args, output, size;
    } cases[] = {
        {"bake " + scene + " --res 96 --dense -o " + mnt + "/f.sdfg", "f.sdfg", "256k"},
        {"bake " + scene + " --res 96 --dense -o " + mnt + "/f.sdf", "f.sdf", "256k"},
        {"bake " + scene + " --res 96 --dense -o " + mnt + "/f.vdb", "f.vdb", "256k"},
        {"bake " + scene + " --res 96 --dense -o " + mnt + "/f.raw", "f.raw", "256k"},
        {"render " + scene + close + "-o " + mnt + "/a.exr", "a.exr", "8k"},
        {"render " + scene + close + "-o " + mnt + "/a.pfm", "a.pfm", "8k"},
        {"render " + scene + close + "-o " + mnt + "/a.png", "a.png", "8k"},
    };
    for (const Case& c : cases) {
        // Mount, run, and list what is left, all inside the namespace.
        const std::string listing = dir.file("listing.txt");
        RunResult r = runShell("unshare -rm sh -c 'mount -t tmpfs -o size=" + c.size + " none " +
                                   mnt + " && " + SDFT_CLI_PATH + " " + c.args + "; s=$?; ls -A " +
                                   mnt + " > " + listing + "; exit $s'",
                               dir);
        EXPECT_NE(r.status, 0) << c.args;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_NE(r.err.find(c.output + ": cannot write the output file (No space left on device: "
                                        "the file system is full); nothing was written there"),
                  std::string::npos)
            << c.args << ": " << r.err;
        EXPECT_EQ(readFile(listing), "") << c.args << ": left behind";
    }
}

// The same through a file-size limit (ulimit -f), which needs no mount.
TEST(WriteFaults, FileSizeLimitLeavesNothingAndSaysSo) {
    TempDir dir;
    const std::string scene = dir.write("scene.json", kScene);
    RunResult r = runShell("trap '' XFSZ; ulimit -f 64; exec " + std::string(SDFT_CLI_PATH) +
                               " bake " + scene + " --res 96 --dense -o " + dir.file("f.sdfg"),
                           dir);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("f.sdfg: cannot write the output file (File too large: over the "
                         "file-size limit"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(joined(filesIn(dir.path())), "scene.json ");
}

// The output directory is removed while the render runs: either the start-up check or the final
// write reports it; nothing appears.
TEST(WriteFaults, VanishingOutputDirectoryIsReported) {
    TempDir dir;
    const std::string scene = dir.write(
        "scene.json",
        std::string(kScene).insert(1, R"("render": {"integrator": "path", "spp": 64}, )"));
    const std::string sub = dir.file("out");
    std::filesystem::create_directory(sub);
    const std::string err = dir.file("err.txt");
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        const std::string cmd = std::string(SDFT_CLI_PATH) + " render " + scene +
                                " -q --width 320 --height 240 -o " + sub + "/a.png 2>" + err;
        execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
        _exit(127);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(150));
    std::filesystem::remove_all(sub);
    int status = 0;
    waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_NE(WEXITSTATUS(status), 0);
    const std::string message = readFile(err);
    EXPECT_NE(message.find("a.png"), std::string::npos) << message;
    EXPECT_TRUE(message.find("directory " + sub + " no longer exists") != std::string::npos ||
                message.find("directory " + sub + " does not exist") != std::string::npos)
        << message;
    EXPECT_FALSE(std::filesystem::exists(sub));
}

// SIGKILL or SIGTERM at several moments of a bake that writes a 45 MB grid: the output path
// holds nothing or the whole grid, never a part; after SIGTERM no temporary file remains either.
TEST(WriteFaults, KillDuringAWriteNeverLeavesAPartialFile) {
    TempDir dir;
    const std::string scene = dir.write("scene.json", kScene);
    const std::string out = dir.file("f.sdfg");
    auto start = [&] {
        const pid_t pid = fork();
        if (pid == 0) {
            const std::string cmd = std::string(SDFT_CLI_PATH) + " bake " + scene +
                                    " --res 224 --dense --threads 1 -o " + out + " 2>/dev/null";
            execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
            _exit(127);
        }
        return pid;
    };
    auto temporaries = [&] {
        int n = 0;
        for (const auto& e : std::filesystem::directory_iterator(dir.path()))
            n += e.path().filename().string().find(".tmp.") != std::string::npos;
        return n;
    };
    int complete = 0, absent = 0;
    const int delays[] = {50, 200, 350, 500, 650, 800, 1000, 1300};
    for (size_t i = 0; i < std::size(delays); ++i) {
        const int sig = i % 2 ? SIGTERM : SIGKILL;
        std::filesystem::remove(out);
        const pid_t pid = start();
        ASSERT_GT(pid, 0);
        std::this_thread::sleep_for(std::chrono::milliseconds(delays[i]));
        kill(pid, sig);
        waitpid(pid, nullptr, 0);
        if (sig == SIGTERM) {
            EXPECT_EQ(temporaries(), 0) << "after SIGTERM at " << delays[i] << " ms";
        }
        for (const auto& e : std::filesystem::directory_iterator(dir.path()))
            if (e.path().filename().string().find(".tmp.") != std::string::npos)
                std::filesystem::remove(e.path());  // SIGKILL cannot clean up
        if (!std::filesystem::exists(out)) {
            ++absent;
            continue;
        }
        RunResult info = runCli("info " + out, dir);
        EXPECT_EQ(info.status, 0) << "a partial grid after signal " << sig << " at " << delays[i]
                                  << " ms: " << info.err;
        ++complete;
    }
    std::printf("killed %d times before the rename (no file), %d after (the whole grid)\n", absent,
                complete);
}

}  // namespace
}  // namespace sdft::e2e
