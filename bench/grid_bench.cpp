// Jamriška 2010, Tables 1-4, on the Stanford bunny (data/meshes/bunny_npm.obj, closed) made a level
// set by OpenVDB's meshToLevelSet at about 128, 256 and 512 cells across, rendered 512x512 with 1
// and 2 threads, and OpenVDB's LevelSetRayIntersector on the same level set and camera as the
// baseline, all in one run; and primary rays one by one against packets of eight (decision 25).
//
//   build/release/bench/sdftrace_grid_bench --benchmark_repetitions=5
//   --benchmark_report_aggregates_only=true
//
// Counters: trav_steps_k / isect_tests_k / interpolations_k (thousands per image, as in the paper's
// tables), hits, mismatch (hit/miss disagreements with OpenVDB off silhouettes), ms per image.
#include <benchmark/benchmark.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/RayIntersector.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>

#include "sdftrace/io/vdb_io.h"
#include "sdftrace/math/camera.h"
#include "sdftrace/scene/grid_scene.h"
#include "sdftrace/trace/grid_tracer.h"
#include "sdftrace/trace/minmax_buffer.h"

namespace sdft {
namespace {

constexpr int kImage = 512;

struct Mesh {
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
};

// Positions and faces (fan-triangulated) of an OBJ file; enough for the benchmark's bunny.
Mesh loadObj(const std::string& path) {
    Mesh m;
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream s(line);
        std::string tag;
        s >> tag;
        if (tag == "v") {
            float x, y, z;
            s >> x >> y >> z;
            m.points.emplace_back(x, y, z);
        } else if (tag == "f") {
            std::vector<unsigned> idx;
            std::string tok;
            while (s >> tok)
                idx.push_back(static_cast<unsigned>(std::stoul(tok.substr(0, tok.find('/')))) - 1);
            for (size_t i = 2; i < idx.size(); ++i)
                m.triangles.emplace_back(idx[0], idx[i - 1], idx[i]);
        }
    }
    if (m.points.empty()) throw std::runtime_error(path + ": no vertices");
    return m;
}

struct Level {
    openvdb::FloatGrid::Ptr vdb;
    std::shared_ptr<Grid> grid;
    CameraDesc camera;
};

const Level& level(int resolution) {
    static std::map<int, Level> cache;
    auto it = cache.find(resolution);
    if (it != cache.end()) return it->second;
    openvdb::initialize();
    static Mesh mesh = loadObj(std::string(SDFT_SOURCE_DIR) + "/data/meshes/bunny_npm.obj");
    openvdb::BBoxd box;
    for (const auto& p : mesh.points) box.expand(openvdb::Vec3d(p));
    double voxel = box.extents()[box.maxExtent()] / resolution;
    auto xf = openvdb::math::Transform::createLinearTransform(voxel);
    Level l;
    l.vdb =
        openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xf, mesh.points, mesh.triangles, 3.0f);
    // Through a file, as a user's level set would arrive.
    std::string path = "/tmp/sdftrace-bench-bunny-" + std::to_string(resolution) + ".vdb";
    openvdb::io::File(path).write({l.vdb});
    l.grid = std::make_shared<Grid>(loadVdb(path));
    std::remove(path.c_str());
    l.camera = frameBounds(l.grid->surfaceBounds(), 35.0f, kImage, kImage);
    return cache.emplace(resolution, std::move(l)).first->second;
}

// Runs `perPixel(x, y)` over the image on exactly `threads` threads, rows in parallel.
template <class F>
void forPixels(int threads, F&& perPixel) {
    tbb::task_arena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, kImage),
                          [&](const tbb::blocked_range<int>& rows) {
                              for (int y = rows.begin(); y != rows.end(); ++y)
                                  for (int x = 0; x < kImage; ++x) perPixel(x, y);
                          });
    });
}

std::vector<uint8_t> vdbHits(const Level& l, int threads) {
    std::vector<uint8_t> hits(kImage * kImage);
    Camera cam(l.camera);
    tbb::enumerable_thread_specific<openvdb::tools::LevelSetRayIntersector<openvdb::FloatGrid>>
        isect([&] { return openvdb::tools::LevelSetRayIntersector<openvdb::FloatGrid>(*l.vdb); });
    forPixels(threads, [&](int x, int y) {
        Ray r = cam.pixelRay(x, y);
        openvdb::math::Ray<double> ray(openvdb::Vec3d(r.origin.x, r.origin.y, r.origin.z),
                                       openvdb::Vec3d(r.direction.x, r.direction.y, r.direction.z));
        openvdb::Vec3d xyz;
        double t;
        hits[y * kImage + x] = isect.local().intersectsWS(ray, xyz, t);
    });
    return hits;
}

int mismatchesOffSilhouettes(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
    int n = 0;
    for (int y = 1; y < kImage - 1; ++y)
        for (int x = 1; x < kImage - 1; ++x) {
            int i = y * kImage + x;
            bool edge = false;
            for (int d : {-1, 1, -kImage, kImage}) edge |= b[i] != b[i + d];
            n += !edge && a[i] != b[i];
        }
    return n;
}

// Table 3: primary rays, without and with min/max buffers; and OpenVDB.
void Primary(benchmark::State& state, int resolution, int threads, int minmax, bool openVdb) {
    const Level& l = level(resolution);
    Camera cam(l.camera);
    GridView g = l.grid->view();
    GridTraceOptions o;
    std::vector<uint8_t> hits(kImage * kImage);
    // Per-pixel counters, like the AOVs (no shared counter between the threads).
    std::vector<int> steps(kImage * kImage), tests(kImage * kImage);
    for (auto _ : state) {
        if (openVdb) {
            hits = vdbHits(l, threads);
            continue;
        }
        MinMaxBuffer buf;
        // Per frame, as in the paper, on the same number of threads as the traversal.
        if (minmax > 0)
            tbb::task_arena(threads).execute([&] { buf = MinMaxBuffer::build(g, cam, minmax); });
        forPixels(threads, [&](int x, int y) {
            Ray r = cam.pixelRay(x, y);
            float t0 = 0, t1 = 1e30f;
            if (minmax > 0) buf.range(x, y, t0, t1);
            GridTraceResult res = t0 <= t1 ? traceGridRay(g, r, t0, t1, o) : GridTraceResult{};
            hits[y * kImage + x] = res.hit;
            steps[y * kImage + x] = res.traversalSteps;
            tests[y * kImage + x] = res.intersectionTests;
        });
    }
    long hitCount = 0;
    for (uint8_t h : hits) hitCount += h;
    state.counters["hits"] = static_cast<double>(hitCount);
    if (!openVdb) {
        state.counters["trav_steps_k"] = std::accumulate(steps.begin(), steps.end(), 0L) / 1000.0;
        state.counters["isect_tests_k"] = std::accumulate(tests.begin(), tests.end(), 0L) / 1000.0;
        state.counters["mismatch"] = mismatchesOffSilhouettes(hits, vdbHits(l, threads));
    }
}

// Table 1: surface cell intersection methods (one thread).
void Cells(benchmark::State& state, int resolution, CellIntersection method, int iters) {
    const Level& l = level(resolution);
    Camera cam(l.camera);
    GridView g = l.grid->view();
    GridTraceOptions o;
    o.cellMethod = method;
    o.falsiIters = iters;
    long interpolations = 0;
    for (auto _ : state) {
        interpolations = 0;
        forPixels(1, [&](int x, int y) {
            GridTraceResult r = traceGridRay(g, cam.pixelRay(x, y), 0, 1e30f, o);
            interpolations += r.interpolations;
        });
    }
    state.counters["interpolations_k"] = interpolations / 1000.0;
}

// Table 2: gradient estimators at every hit point (one thread; the hits are found once, outside).
void Normals(benchmark::State& state, int resolution, GridNormal method) {
    const Level& l = level(resolution);
    Camera cam(l.camera);
    GridView g = l.grid->view();
    std::vector<Vec3> points;
    forPixels(1, [&](int x, int y) {
        Ray r = cam.pixelRay(x, y);
        GridTraceResult res = traceGridRay(g, r, 0, 1e30f, GridTraceOptions{});
        if (res.hit) points.push_back(r.at(res.t));
    });
    for (auto _ : state) {
        Vec3 sum(0.0f);
        for (const Vec3& p : points) sum += gridNormal(g, p, method);
        benchmark::DoNotOptimize(sum);
    }
    state.counters["points"] = static_cast<double>(points.size());
}

// Primary rays one by one against packets of eight (traceGridRays), one thread, in the renderer's
// order: tiles of 16x16 pixels, rows of a tile in turn. The framed camera and a close one (the eye
// at 0.4 of the distance, the bunny filling the view).
void Packets(benchmark::State& state, int resolution, bool close, bool packets) {
    const Level& l = level(resolution);
    CameraDesc cd = l.camera;
    if (close) cd.eye = cd.target + (cd.eye - cd.target) * 0.4f;
    const Camera cam(cd);
    constexpr int kTile = 16;
    std::vector<Ray> rays;
    for (int ty = 0; ty < kImage; ty += kTile)
        for (int tx = 0; tx < kImage; tx += kTile)
            for (int y = ty; y < ty + kTile; ++y)
                for (int x = tx; x < tx + kTile; ++x) rays.push_back(cam.pixelRay(x, y));
    const std::vector<float> tMin(rays.size(), 0.0f), tMax(rays.size(), 1e30f);
    std::vector<GridTraceResult> out(kTile * kTile);
    GridTraceOptions o;
    o.packets = packets;
    long steps = 0, hits = 0;
    double seconds = 0;
    for (auto _ : state) {
        const auto start = std::chrono::steady_clock::now();
        steps = hits = 0;
        for (size_t i = 0; i < rays.size(); i += out.size()) {
            traceGridRays(l.grid->view(), &rays[i], &tMin[i], &tMax[i], kTile * kTile, o,
                          out.data());
            for (const GridTraceResult& r : out) {
                steps += r.traversalSteps;
                hits += r.hit;
            }
        }
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    state.counters["ns_per_ray"] =
        seconds * 1e9 / (static_cast<double>(state.iterations()) * rays.size());
    state.counters["steps_per_ray"] = static_cast<double>(steps) / rays.size();
    state.counters["hits"] = static_cast<double>(hits);
}

// Table 4: shadow rays to five directional lights from every hit, plain vs occluder traversal.
void Shadows(benchmark::State& state, int resolution, int threads, int occluder) {
    const Level& l = level(resolution);
    Camera cam(l.camera);
    GridView g = l.grid->view();
    GridTraceOptions o;
    const Vec3 lights[5] = {normalize(Vec3(-0.4f, 1, 0.5f)), normalize(Vec3(0.6f, 1, 0.2f)),
                            normalize(Vec3(0, 1, -0.7f)), normalize(Vec3(-0.8f, 0.6f, -0.2f)),
                            normalize(Vec3(0.3f, 0.5f, 0.9f))};
    struct Start {
        Vec3 p, n;
    };
    std::vector<Start> starts;
    forPixels(1, [&](int x, int y) {
        Ray r = cam.pixelRay(x, y);
        GridTraceResult res = traceGridRay(g, r, 0, 1e30f, o);
        if (res.hit) {
            Vec3 p = r.at(res.t);
            starts.push_back({p, gridNormal(g, p, GridNormal::InterpolationOfDifferences)});
        }
    });
    std::vector<int> steps(starts.size()), tests(starts.size()), blocked(starts.size());
    const float offset = g.shape.voxelSize;
    for (auto _ : state) {
        tbb::task_arena arena(threads);
        arena.execute([&] {
            tbb::parallel_for(size_t(0), starts.size(), [&](size_t i) {
                steps[i] = tests[i] = blocked[i] = 0;
                for (const Vec3& l : lights) {
                    if (dot(starts[i].n, l) <= 0) continue;
                    GridTraceResult r = traceGridShadow(g, {starts[i].p + starts[i].n * offset, l},
                                                        0, 1e30f, o, occluder);
                    steps[i] += r.traversalSteps;
                    tests[i] += r.intersectionTests;
                    blocked[i] += r.hit;
                }
            });
        });
    }
    state.counters["trav_steps_k"] = std::accumulate(steps.begin(), steps.end(), 0L) / 1000.0;
    state.counters["isect_tests_k"] = std::accumulate(tests.begin(), tests.end(), 0L) / 1000.0;
    state.counters["blocked"] =
        static_cast<double>(std::accumulate(blocked.begin(), blocked.end(), 0L));
}

void registerAll() {
    auto reg = [](const std::string& name, auto fn) {
        benchmark::RegisterBenchmark(name.c_str(), fn)
            ->Unit(benchmark::kMillisecond)
            ->MinTime(0.5)
            ->UseRealTime();
    };
    for (int res : {128, 256, 512}) {
        std::string r = std::to_string(res);
        for (int threads : {1, 2}) {
            std::string t = "/threads:" + std::to_string(threads);
            reg("Primary/bunny" + r + t + "/openvdb",
                [=](benchmark::State& s) { Primary(s, res, threads, 0, true); });
            reg("Primary/bunny" + r + t + "/dda",
                [=](benchmark::State& s) { Primary(s, res, threads, 0, false); });
            for (int mm : {64, 128, 256})
                reg("Primary/bunny" + r + t + "/dda+minmax" + std::to_string(mm),
                    [=](benchmark::State& s) { Primary(s, res, threads, mm, false); });
            for (int n : {0, 12, 32})
                reg("Shadows/bunny" + r + t + (n ? "/occluder" + std::to_string(n) : "/plain"),
                    [=](benchmark::State& s) { Shadows(s, res, threads, n); });
        }
        for (bool close : {false, true})
            for (bool packets : {false, true})
                reg("Packets/bunny" + r + (close ? "/close" : "/framed") +
                        (packets ? "/packets" : "/single"),
                    [=](benchmark::State& s) { Packets(s, res, close, packets); });
        reg("Cells/bunny" + r + "/midpoint",
            [=](benchmark::State& s) { Cells(s, res, CellIntersection::Midpoint, 1); });
        reg("Cells/bunny" + r + "/false-position-1",
            [=](benchmark::State& s) { Cells(s, res, CellIntersection::FalsePosition, 1); });
        reg("Cells/bunny" + r + "/false-position-4",
            [=](benchmark::State& s) { Cells(s, res, CellIntersection::FalsePosition, 4); });
        reg("Normals/bunny" + r + "/analytic",
            [=](benchmark::State& s) { Normals(s, res, GridNormal::AnalyticTrilinear); });
        reg("Normals/bunny" + r + "/difference-of-interpolations",
            [=](benchmark::State& s) { Normals(s, res, GridNormal::DifferenceOfInterpolations); });
        reg("Normals/bunny" + r + "/interpolation-of-differences",
            [=](benchmark::State& s) { Normals(s, res, GridNormal::InterpolationOfDifferences); });
    }
}

}  // namespace
}  // namespace sdft

int main(int argc, char** argv) {
    sdft::registerAll();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
