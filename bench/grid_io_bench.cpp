// Getting grids in and out, against OpenVDB, on meshes of several kinds and sizes, in one run:
// each mesh is baked by `sdftrace bake --res R` (its write phase against its total, from the
// bake's phase line) and converted to a .vdb level set (`sdftrace convert`); then, each in a
// process of its own so that its peak memory is its own (wait4's maximum resident set):
//  - sdftrace load: loadSdfg of the .sdfg (what `render` and `view` do first);
//  - OpenVDB read: openvdb::io::File::readGrid of the .vdb, no delayed loading (what an OpenVDB
//    program does first);
//  - sdftrace import: loadVdb of the same .vdb;
//  - info: `sdftrace info` of the .sdfg (its header and block table).
// Times are medians of --reps runs, the kinds alternating; peaks are medians too, and given
// against the grid that process made (Grid::memoryBytes; the import keeps the .vdb's band, so its
// grid is larger than the .sdfg's) less the process's own (this program
// loading nothing: its libraries, some 40 MiB).
//
//   build/release/bench/sdftrace_grid_io_bench [--res 2048] [--reps 5] [--dir /tmp] [--keep]
//       mesh.obj|ply ...
//
// Prints a markdown table on stdout.
#include <fcntl.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "sdftrace/core/error.h"
#include "sdftrace/io/sdfg_io.h"
#include "sdftrace/io/vdb_io.h"

extern char** environ;

namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0 : v[v.size() / 2];
}

// One process: argv run, its stdout and stderr captured in files; its peak resident set (MiB)
// from wait4.
struct Run {
    int status = -1;
    std::string out, err;
    double peakMiB = 0, wall = 0;
};

std::string slurp(const std::string& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

Run run(const std::vector<std::string>& args) {
    const std::string outPath = "/tmp/sdftrace-grid-io-bench.out",
                      errPath = "/tmp/sdftrace-grid-io-bench.err";
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, outPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
    posix_spawn_file_actions_addopen(&actions, 2, errPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    Run r;
    const auto t0 = Clock::now();
    pid_t pid = 0;
    if (posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ) == 0) {
        int status = 0;
        rusage usage{};
        wait4(pid, &status, 0, &usage);
        r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        r.peakMiB = static_cast<double>(usage.ru_maxrss) / 1024.0;  // KiB on Linux
    }
    r.wall = seconds(t0);
    posix_spawn_file_actions_destroy(&actions);
    r.out = slurp(outPath);
    r.err = slurp(errPath);
    return r;
}

// The number after `key` in `text` (0 when absent).
double numberAfter(const std::string& text, const std::string& key) {
    const size_t at = text.find(key);
    return at == std::string::npos ? 0 : std::atof(text.c_str() + at + key.size());
}

// --child MODE FILE: one load in this process; prints its seconds and the grid's MiB.
int child(const std::string& mode, const std::string& file) {
    try {
        const auto t0 = Clock::now();
        double memory = 0;
        if (mode == "sdfg") {
            memory = static_cast<double>(sdft::loadSdfg(file).memoryBytes());
        } else if (mode == "import") {
            memory = static_cast<double>(sdft::loadVdb(file).memoryBytes());
        } else if (mode == "baseline") {  // the process alone: what every peak includes
            openvdb::initialize();
        } else if (mode == "openvdb") {
            openvdb::initialize();
            openvdb::io::File f(file);
            f.open(false);  // no delayed loading: the whole grid read now
            const auto grid = f.readGrid("surface");
            memory = static_cast<double>(grid->memUsage());
        } else {
            return 2;
        }
        std::printf("%.6f %.3f\n", seconds(t0), memory / 1048576.0);
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
}

struct Timing {
    std::vector<double> seconds, peak;
    double memoryMiB = 0;
};

// One mesh: its bake at `res` cells (the write phase from the bake's phase line), the .vdb
// converted from it, then `reps` rounds of the loads, each in a process of its own; prints its
// table row.
void benchMesh(const std::string& mesh, int res, int reps, const std::string& dir, bool keep) {
    const std::string self = std::filesystem::canonical("/proc/self/exe").string();
    const std::string cli = SDFT_CLI_PATH;
    const std::string name = std::filesystem::path(mesh).stem().string();
    const std::string sdfg = dir + "/" + name + "-" + std::to_string(res) + ".sdfg",
                      vdb = dir + "/" + name + "-" + std::to_string(res) + ".vdb";
    const Run bake = run({cli, "bake", mesh, "--res", std::to_string(res), "-o", sdfg});
    if (bake.status != 0) {
        std::fprintf(stderr, "%s: bake failed: %s\n", mesh.c_str(), bake.err.c_str());
        return;
    }
    const double write = numberAfter(bake.err, "write "), total = numberAfter(bake.err, "total ");
    const Run convert = run({cli, "convert", sdfg, vdb});
    const bool haveVdb = convert.status == 0;
    Timing load, read, import, base;
    std::vector<double> info;
    for (int r = 0; r < reps; ++r) {
        auto once = [&](const std::string& mode, const std::string& file, Timing& t) {
            const Run c = run({self, "--child", mode, file});
            if (c.status != 0) {
                std::fprintf(stderr, "%s %s: %s", mode.c_str(), file.c_str(), c.err.c_str());
                return;
            }
            double s = 0;
            std::sscanf(c.out.c_str(), "%lf %lf", &s, &t.memoryMiB);
            t.seconds.push_back(s);
            t.peak.push_back(c.peakMiB);
        };
        once("baseline", sdfg, base);
        once("sdfg", sdfg, load);
        if (haveVdb) {
            once("openvdb", vdb, read);
            once("import", vdb, import);
        }
        info.push_back(run({cli, "info", sdfg}).wall);
    }
    const double grid = load.memoryMiB;
    auto peakOf = [&](const Timing& t) { return median(t.peak); };
    // Each peak against the grid that process made (the import's band is the .vdb's, wider
    // than the bake's, so its grid is larger than the .sdfg's).
    auto overGrid = [&](const Timing& t) {
        return t.memoryMiB > 0 ? (peakOf(t) - peakOf(base)) / t.memoryMiB : 0.0;
    };
    char row[1024];
    std::snprintf(
        row, sizeof row,
        "| %s | %d | %.0f MiB | %.0f / %.0f MB | %.2f / %.1f s (%.0f %%) | %.2f s (%.0f MiB, "
        "%.2fx) | %.2f s (%.0f MiB) | %.2fx | %.0f MiB | %.2f s (%.0f MiB, %.2fx) | %.2fx | %.0f "
        "ms |\n",
        name.c_str(), res, grid, std::filesystem::file_size(sdfg) / 1e6,
        haveVdb ? std::filesystem::file_size(vdb) / 1e6 : 0.0, write, total,
        total > 0 ? 100 * write / total : 0.0, median(load.seconds), peakOf(load), overGrid(load),
        median(read.seconds), peakOf(read),
        median(load.seconds) > 0 ? median(read.seconds) / median(load.seconds) : 0.0,
        import.memoryMiB, median(import.seconds), peakOf(import), overGrid(import),
        median(import.seconds) > 0 ? median(read.seconds) / median(import.seconds) : 0.0,
        1000 * median(info));
    std::fputs(row, stdout);
    std::fflush(stdout);
    if (!keep) {
        std::filesystem::remove(sdfg);
        std::filesystem::remove(vdb);
    }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc == 4 && std::string(argv[1]) == "--child") return child(argv[2], argv[3]);
    int res = 2048, reps = 5;
    bool keep = false;
    std::string dir = "/tmp";
    std::vector<std::string> meshes;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--res" && i + 1 < argc)
            res = std::atoi(argv[++i]);
        else if (a == "--reps" && i + 1 < argc)
            reps = std::max(1, std::atoi(argv[++i]));
        else if (a == "--dir" && i + 1 < argc)
            dir = argv[++i];
        else if (a == "--keep")
            keep = true;
        else
            meshes.push_back(a);
    }
    if (meshes.empty()) {
        std::fprintf(stderr,
                     "usage: sdftrace_grid_io_bench [--res 2048] [--reps 5] [--dir /tmp] "
                     "[--keep] mesh ...\n");
        return 2;
    }
    std::printf(
        "| mesh | cells | grid | .sdfg / .vdb | bake: write / total | sdftrace load (peak, "
        "x grid over the process) | OpenVDB read (peak) | read / load | imported grid | "
        "sdftrace import (peak, x its grid) | read / import | info |\n| --- | --- | --- | --- | "
        "--- | --- | --- | --- | --- | --- | --- | --- |\n");
    for (const std::string& mesh : meshes) benchMesh(mesh, res, reps, dir, keep);
    return 0;
}
