// Runs the sdftrace binary as a user would and captures its exit status and output.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace sdft::e2e {

struct RunResult {
    int status = -1;
    std::string out, err;
};

inline std::string readFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

// A fresh directory per test, removed at the end.
class TempDir {
  public:
    TempDir() {
        char tmpl[] = "/tmp/sdftrace-test-XXXXXX";
        m_path = ::mkdtemp(tmpl);
    }
    ~TempDir() { std::filesystem::remove_all(m_path); }
    std::string file(const std::string& name) const { return m_path + "/" + name; }
    std::string write(const std::string& name, const std::string& text) const {
        std::ofstream(file(name), std::ios::binary) << text;
        return file(name);
    }
    // Names of the files in the directory (to check no output or temporary file was left).
    int count() const {
        int n = 0;
        for (auto& e : std::filesystem::directory_iterator(m_path))
            n += e.is_regular_file() ? 1 : 0;
        return n;
    }
    const std::string& path() const { return m_path; }

  private:
    std::string m_path;
};

// Reads a PFM written by sdftrace (rows bottom to top) into top-to-bottom rows.
inline std::vector<float> readPfm(const std::string& path, int& w, int& h, int& channels) {
    std::string data = readFile(path);
    char kind[3] = {};
    float scale;
    int consumed = 0;
    if (std::sscanf(data.c_str(), "%2s %d %d %f%n", kind, &w, &h, &scale, &consumed) != 4)
        return {};
    channels = std::string(kind) == "PF" ? 3 : 1;
    size_t offset = consumed + 1;
    std::vector<float> out(static_cast<size_t>(w) * h * channels);
    for (int y = 0; y < h; ++y)  // PFM rows run bottom to top
        std::memcpy(out.data() + static_cast<size_t>(h - 1 - y) * w * channels,
                    data.data() + offset + static_cast<size_t>(y) * w * channels * 4,
                    w * channels * 4);
    return out;
}

// Whether interior pixel i of a depth image (width w) has a 4-neighbour with the other hit/miss
// state.
inline bool onSilhouette(const std::vector<float>& depth, int w, int i) {
    for (int d : {-1, 1, -w, w})
        if (std::isfinite(depth[i]) != std::isfinite(depth[i + d])) return true;
    return false;
}

// `prefix` goes before the binary (environment settings, a wrapper such as xvfb-run).
inline RunResult runCli(const std::string& args, const TempDir& dir,
                        const std::string& prefix = "") {
    std::string out = dir.path() + "/.stdout", err = dir.path() + "/.stderr";
    std::string cmd =
        prefix + std::string(SDFT_CLI_PATH) + " " + args + " >" + out + " 2>" + err + " </dev/null";
    int raw = std::system(cmd.c_str());
    RunResult r;
    r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    r.out = readFile(out);
    r.err = readFile(err);
    std::filesystem::remove(out);
    std::filesystem::remove(err);
    return r;
}

// The shared libraries the CLI loads at start, as the dynamic loader lists them.
inline std::string librariesLoadedAtStart() {
    std::string libs;
    FILE* p = popen(("LD_TRACE_LOADED_OBJECTS=1 " + std::string(SDFT_CLI_PATH)).c_str(), "r");
    if (!p) return libs;
    char buf[4096];
    for (size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) libs.append(buf, n);
    pclose(p);
    return libs;
}

}  // namespace sdft::e2e
