// Mesh bakes, every method, against OpenVDB's meshToLevelSet at the same voxel size and band, in
// one run (issue 4's benchmark). Each case runs in a forked child, so its peak memory is its own;
// times are medians of --reps runs of the bake alone (mesh loading excluded, BVH builds included).
// Accuracy: |baked - exact| in voxels over the stored samples within the band (up to 200k of
// them, evenly strided), exact = closest-point distance signed by the winding number (the
// hierarchical sum, or the exact one where that is within 0.1 of 1/2).
//
//   build/release/bench/sdftrace_bake_bench                      # bunny + teapot, everything
//   build/release/bench/sdftrace_bake_bench --meshes bunny,/tmp/sdftrace-meshes/rock.ply
//       --sparse 256 --dense none
//       --methods exact,openvdb --threads 2 --reps 5
//   build/release/bench/sdftrace_bake_bench --sparse none --dense 128,256
//       --methods exact,exact-bvh --threads 1,2 --reps 3   # closest point transform vs BVH
//
// Prints a markdown table on stdout.
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "bench_flags.h"
#include "sdftrace/bake/exact_bake.h"
#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/bake/winding_number.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/io/mesh_io.h"

using namespace sdft;

namespace {

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream in(s);
    for (std::string part; std::getline(in, part, ',');) out.push_back(part);
    return out;
}

struct Result {
    double ms = 0, peakMiB = 0, gridMiB = 0, meanErr = 0, maxErr = 0, wrongSign = 0;
    size_t checked = 0;
};

struct Case {
    std::string meshName, method;
    int resolution = 128;
    bool dense = false;
    int threads = 1;
};

// Error statistics of (baked, exact) pairs in voxels.
struct Errors {
    double sum = 0, max = 0;
    size_t n = 0, wrong = 0;
    void add(float baked, float exact, float h) {
        double e = std::fabs(std::fabs(baked) - std::fabs(exact)) / h;  // signs counted apart
        sum += e, max = std::max(max, e), ++n;
        wrong += std::fabs(exact) > 0.01f * h && (baked < 0) != (exact < 0);
    }
};

Result runOnce(const TriangleMesh& mesh, const Case& c, bool measure) {
    const float band = 3;
    SampleOptions so;
    so.resolution = c.resolution;
    so.kind = c.dense ? GridKind::Dense : GridKind::Sparse;
    so.bandVoxels = band;
    so.threads = c.threads;
    GridShape shape = gridShapeFor(mesh.bounds(), so);
    const float h = shape.voxelSize;
    Result r;
    MeshBvh bvh(mesh);
    WindingNumber winding(mesh);
    auto exactAt = [&](Vec3 p) {
        float d = bvh.closestDistance(p);
        // The hierarchical sum errs by a few percent: the exact one where it is that close to 1/2.
        double w = winding.fast(p);
        if (std::fabs(w - 0.5) < 0.1) w = winding.exact(p);
        return w > 0.5 ? -d : d;
    };
    Errors err;
    tbb::task_arena arena(c.threads);
    if (c.method == "openvdb") {
        std::vector<openvdb::Vec3s> points;
        std::vector<openvdb::Vec3I> tris;
        auto xf = openvdb::math::Transform::createLinearTransform(h);
        for (Vec3 p : mesh.positions) points.push_back({p.x, p.y, p.z});  // world space
        for (const auto& t : mesh.triangles) tris.push_back({t[0], t[1], t[2]});
        openvdb::FloatGrid::Ptr grid;
        auto t0 = std::chrono::steady_clock::now();
        arena.execute([&] {
            grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xf, points, tris, band);
        });
        r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                   .count();
        r.gridMiB = grid->memUsage() / 1048576.0;
        if (measure) {
            size_t active = grid->activeVoxelCount(), stride = std::max<size_t>(1, active / 200000),
                   n = 0;
            for (auto it = grid->cbeginValueOn(); it; ++it, ++n) {
                if (n % stride) continue;
                openvdb::Vec3d w = xf->indexToWorld(it.getCoord());
                float ex = exactAt(Vec3(w.x(), w.y(), w.z()));
                if (std::fabs(ex) < band * h) err.add(*it, ex, h);
            }
        }
    } else {
        MeshBakeOptions o;
        // exact-bvh: the dense exact bake by a BVH query per vertex (the transform's baseline).
        if (c.method == "exact-bvh") {
            o.method = MeshBakeMethod::Exact;
            o.closest = ClosestPoints::Bvh;
        } else if (!parseMeshBakeMethod(c.method, o.method)) {
            std::fprintf(stderr, "unknown method %s\n", c.method.c_str());
            std::exit(2);
        }
        o.sampling = so;
        auto t0 = std::chrono::steady_clock::now();
        Grid g = bakeMesh(mesh, o).grid;
        r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                   .count();
        r.gridMiB = g.memoryBytes() / 1048576.0;
        if (measure) {
            GridView v = g.view();
            const GridShape& s = g.shape();
            size_t total = s.vertexCount(), stride = std::max<size_t>(1, total / 4000000);
            std::vector<std::array<int, 3>> band3;
            for (size_t idx = 0; idx < total; idx += stride) {
                int i = idx % (s.cells[0] + 1), j = (idx / (s.cells[0] + 1)) % (s.cells[1] + 1),
                    k = idx / ((s.cells[0] + 1) * size_t(s.cells[1] + 1));
                if (v.kind == GridKind::Sparse) {  // stored samples only (not the background)
                    int B = v.blockSize;
                    int bi = std::min(i, s.cells[0] - 1) / B, bj = std::min(j, s.cells[1] - 1) / B,
                        bk = std::min(k, s.cells[2] - 1) / B;
                    if (v.blockData[v.blockSlot(bi, bj, bk)] < 0) continue;
                }
                if (std::fabs(v.vertex(i, j, k)) < band * h) band3.push_back({i, j, k});
            }
            size_t step = std::max<size_t>(1, band3.size() / 200000);
            for (size_t n = 0; n < band3.size(); n += step) {
                auto [i, j, k] = band3[n];
                Vec3 p = s.origin + Vec3(i, j, k) * h;
                err.add(v.vertex(i, j, k), exactAt(p), h);
            }
        }
    }
    r.checked = err.n;
    r.meanErr = err.n ? err.sum / err.n : 0;
    r.maxErr = err.max;
    r.wrongSign = err.n ? 100.0 * err.wrong / err.n : 0;
    r.peakMiB = peakResidentMiB();
    return r;
}

// Runs the case `reps` times in one child (the first run also measures accuracy); returns the
// median time, the child's peak memory and the accuracy.
Result runCase(const std::string& meshPath, const Case& c, int reps) {
    int fd[2];
    if (pipe(fd) != 0) std::exit(1);
    pid_t pid = fork();
    if (pid == 0) {
        close(fd[0]);
        TriangleMesh mesh = loadMesh(meshPath);
        std::vector<double> times;
        Result first;
        for (int i = 0; i < reps; ++i) {
            Result r = runOnce(mesh, c, i == 0);
            if (i == 0) first = r;
            times.push_back(r.ms);
        }
        std::sort(times.begin(), times.end());
        first.ms = times[times.size() / 2];
        first.peakMiB = peakResidentMiB();
        if (write(fd[1], &first, sizeof first) != sizeof first) _exit(1);
        _exit(0);
    }
    close(fd[1]);
    Result r;
    bool ok = read(fd[0], &r, sizeof r) == sizeof r;
    close(fd[0]);
    int status = 0;
    waitpid(pid, &status, 0);
    if (!ok || status != 0) r.ms = -1;
    return r;
}

}  // namespace

int main(int argc, char** argv) {
    std::string meshes = "bunny,teapot", sparse = "128,256,512", dense = "128,256",
                methods = "exact,jfa,danielsson,edt,rtsdf,openvdb", threads = "1,2";
    int reps = 3;
    constexpr const char* kUsage =
        "usage: sdftrace_bake_bench [--meshes bunny,teapot|PATH,...] [--sparse 128,256,512|none]\n"
        "       [--dense 128,256|none] [--methods exact,jfa,danielsson,edt,rtsdf,openvdb]\n"
        "       [--threads 1,2] [--reps 3]\n";
    if (const int status = bench::checkFlagPairs(argc, argv, kUsage); status >= 0) return status;
    for (int i = 1; i + 1 < argc; i += 2) {
        std::string k = argv[i], v = argv[i + 1];
        if (k == "--meshes")
            meshes = v;
        else if (k == "--sparse" || k == "--dense") {
            if (v != "none") bench::intListFlag(k, v, 2);
            (k == "--sparse" ? sparse : dense) = v;
        } else if (k == "--methods")
            methods = v;
        else if (k == "--threads") {
            bench::intListFlag(k, v);
            threads = v;
        } else if (k == "--reps")
            reps = bench::intFlag(k, v);
        else {
            std::fprintf(stderr, "unknown option %s\n", k.c_str());
            return 2;
        }
    }
    openvdb::initialize();
    std::printf(
        "| mesh | grid | method | threads | ms (median of %d) | peak MiB | grid MiB | band "
        "error mean / max (voxels) | wrong signs in band |\n| --- | --- | --- | --- | --- "
        "| --- | --- | --- | --- |\n",
        reps);
    std::fflush(stdout);
    for (const std::string& m : split(meshes)) {
        // A name of data/meshes ("bunny" is the Stanford scan), or any mesh file's path.
        std::string path = m.find('/') != std::string::npos
                               ? m
                               : std::string(SDFT_SOURCE_DIR) + "/data/meshes/" +
                                     (m == "bunny" ? "stanford-bunny.obj" : m + ".obj");
        for (int pass = 0; pass < 2; ++pass) {
            std::string list = pass == 0 ? sparse : dense;
            if (list == "none") continue;
            for (const std::string& res : split(list))
                for (const std::string& method : split(methods)) {
                    if (pass == 1 && method == "openvdb") continue;  // narrow band only
                    for (const std::string& t : split(threads)) {
                        Case c{m, method, std::stoi(res), pass == 1, std::stoi(t)};
                        Result r = runCase(path, c, reps);
                        if (r.ms < 0) {
                            std::printf("| %s | %s %s | %s | %s | failed |\n", m.c_str(),
                                        pass ? "dense" : "sparse", res.c_str(), method.c_str(),
                                        t.c_str());
                            continue;
                        }
                        std::printf(
                            "| %s | %s %s | %s | %s | %.0f | %.0f | %.1f | %.4f / %.3f | "
                            "%.3f%% |\n",
                            m.c_str(), pass ? "dense" : "sparse", res.c_str(), method.c_str(),
                            t.c_str(), r.ms, r.peakMiB, r.gridMiB, r.meanErr, r.maxErr,
                            r.wrongSign);
                        std::fflush(stdout);
                    }
                }
        }
    }
    return 0;
}
