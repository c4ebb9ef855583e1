// Side-by-side measurements on meshes of different kinds and sizes, in one run: each mesh becomes
// a level set by OpenVDB's meshToLevelSet (band 3) written to a .vdb file, as a user's level set
// would arrive; then, for four cameras (framed automatically, a close-up that fills the frame, a
// grazing view skimming the top of the object, the framed view from four times as far) and two
// image sizes:
//  - render phase: `sdftrace render file.vdb --no-shadows --grid-normals analytic` as a process
//    (the time its summary line gives) against OpenVDB's LevelSetRayIntersector with its normal
//    and a headlight (what a minimal OpenVDB program does) and Embree's rtcIntersect1 on the
//    source triangles with the geometric normal and the same headlight, both in this process on
//    the same threads. Both grid renderers then take the gradient of the trilinear interpolant in
//    the hit's cell as the normal (OpenVDB: BoxStencil::gradient); sdftrace's default, smooth
//    normals from interpolated central differences (32 samples), is timed too (column "smooth");
//  - rays: sdftrace's primary rays with the Embree loop's per-pixel work and no more, in this
//    process (renderGridRays): the render phase's rays without its shading and film;
//  - whole process: the sdftrace process's wall time (PNG written) against the minimal OpenVDB
//    program bench/openvdb_render.cpp as a process (reads the file, renders as above, writes a
//    PPM);
//  - hits: pixels where sdftrace and OpenVDB disagree on hit or miss, off silhouettes.
// Per mesh: importing the .vdb (sdftrace's loadVdb) against OpenVDB's read, and the sparse grid's
// memory against OpenVDB's memUsage for the same band.
// Times are medians of --reps runs.
//
//   build/release/bench/sdftrace_scale_bench [--res 256] [--sizes 512,1024] [--reps 5]
//       [--threads 2] [--keep] [--commands] mesh.obj|ply ...
//
// Prints markdown tables on stdout.
#include <embree3/rtcore.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/RayIntersector.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "bench_flags.h"
#include "sdftrace/io/mesh_io.h"
#include "sdftrace/io/vdb_io.h"
#include "sdftrace/math/camera.h"
#include "sdftrace/render/render_settings.h"
#include "sdftrace/scene/grid_scene.h"
#include "sdftrace/trace/grid_tracer.h"
#include "sdftrace/trace/minmax_buffer.h"

using namespace sdft;

namespace {

using Clock = std::chrono::steady_clock;
double ms(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0 : v[v.size() / 2];
}

struct Options {
    int res = 256, reps = 5, threads = 2;
    bool keep = false;      // keep the .vdb files in /tmp
    bool commands = false;  // print each sdftrace command line to stderr (to profile one case)
    std::vector<int> sizes{512, 1024};
    std::vector<std::string> meshes;
};

// Runs `cmd` through the shell; returns its stderr and the wall time in ms.
std::string runProcess(const std::string& cmd, double& wallMs) {
    const std::string errFile = "/tmp/sdftrace-scale-bench-" + std::to_string(getpid()) + ".err";
    const auto t0 = Clock::now();
    const int status = std::system((cmd + " 2>" + errFile).c_str());
    wallMs = ms(t0, Clock::now());
    std::ifstream in(errFile);
    std::stringstream s;
    s << in.rdbuf();
    std::remove(errFile.c_str());
    if (status != 0) {
        std::fprintf(stderr, "failed: %s\n%s", cmd.c_str(), s.str().c_str());
        std::exit(1);
    }
    return s.str();
}

template <class F>
void forPixels(int threads, int w, int h, F&& perPixel) {
    tbb::task_arena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
            for (int y = rows.begin(); y != rows.end(); ++y)
                for (int x = 0; x < w; ++x) perPixel(x, y);
        });
    });
}

// Headlight shading of a hit: what every renderer here writes per pixel.
inline float headlight(Vec3 n, Vec3 d) { return std::max(0.0f, -dot(normalize(n), d)); }

std::vector<uint8_t> renderOpenVdb(const openvdb::FloatGrid& grid, const CameraDesc& cd,
                                   int threads, std::vector<float>& image) {
    Camera cam(cd);
    std::vector<uint8_t> hits(static_cast<size_t>(cd.width) * cd.height);
    image.assign(hits.size(), 0.0f);
    using Isect = openvdb::tools::LevelSetRayIntersector<openvdb::FloatGrid>;
    tbb::enumerable_thread_specific<Isect> isect([&] { return Isect(grid); });
    forPixels(threads, cd.width, cd.height, [&](int x, int y) {
        const Ray r = cam.pixelRay(x, y);
        openvdb::math::Ray<double> ray(openvdb::Vec3d(r.origin.x, r.origin.y, r.origin.z),
                                       openvdb::Vec3d(r.direction.x, r.direction.y, r.direction.z));
        openvdb::Vec3d xyz(0.0), nml(0.0);
        double t;
        const size_t i = static_cast<size_t>(y) * cd.width + x;
        hits[i] = isect.local().intersectsWS(ray, xyz, nml, t);
        if (hits[i])
            image[i] = headlight(Vec3(float(nml[0]), float(nml[1]), float(nml[2])), r.direction);
    });
    return hits;
}

struct EmbreeScene {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    explicit EmbreeScene(const TriangleMesh& m) {
        device = rtcNewDevice(nullptr);
        scene = rtcNewScene(device);
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0,
                                                              RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                              m.positions.size()));
        for (size_t i = 0; i < m.positions.size(); ++i) {
            v[3 * i] = m.positions[i].x;
            v[3 * i + 1] = m.positions[i].y;
            v[3 * i + 2] = m.positions[i].z;
        }
        auto* t = static_cast<uint32_t*>(
            rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                    3 * sizeof(uint32_t), m.triangles.size()));
        for (size_t i = 0; i < m.triangles.size(); ++i)
            for (int c = 0; c < 3; ++c) t[3 * i + c] = m.triangles[i][c];
        rtcCommitGeometry(g);
        rtcAttachGeometry(scene, g);
        rtcReleaseGeometry(g);
        rtcCommitScene(scene);
    }
    ~EmbreeScene() {
        rtcReleaseScene(scene);
        rtcReleaseDevice(device);
    }
};

void renderEmbree(const EmbreeScene& e, const CameraDesc& cd, int threads,
                  std::vector<float>& image) {
    Camera cam(cd);
    image.assign(static_cast<size_t>(cd.width) * cd.height, 0.0f);
    forPixels(threads, cd.width, cd.height, [&](int x, int y) {
        const Ray r = cam.pixelRay(x, y);
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRayHit rh{};
        rh.ray.org_x = r.origin.x, rh.ray.org_y = r.origin.y, rh.ray.org_z = r.origin.z;
        rh.ray.dir_x = r.direction.x, rh.ray.dir_y = r.direction.y, rh.ray.dir_z = r.direction.z;
        rh.ray.tnear = 0;
        rh.ray.tfar = INFINITY;
        rh.ray.mask = ~0u;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(e.scene, &ctx, &rh);
        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID)
            image[static_cast<size_t>(y) * cd.width + x] =
                std::fabs(headlight({rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z}, r.direction));
    });
}

// sdftrace's primary rays as the renderer casts them, with Embree's loop's per-pixel work and no
// more: the min/max buffer (Jamriška §6) built for the camera, then per 16x16 tile the camera rays,
// traceGridRays (packets of eight through the DDA, the eye's sign given), the trilinear
// interpolant's gradient in the hit's cell (the trace's) and the headlight. The render phase adds
// the renderer's shading, AOVs and film on top of this.
void renderGridRays(const Grid& grid, const CameraDesc& cd, int threads,
                    std::vector<float>& image) {
    const Camera cam(cd);
    const GridView g = grid.view();
    image.assign(static_cast<size_t>(cd.width) * cd.height, 0.0f);
    constexpr int kTile = 16;
    const int tilesX = (cd.width + kTile - 1) / kTile, tilesY = (cd.height + kTile - 1) / kTile;
    tbb::task_arena arena(threads);
    arena.execute([&] {
        const MinMaxBuffer minMax = MinMaxBuffer::build(g, cam, RenderSettings{}.minMaxResolution);
        const GridTraceOptions options;
        const float eyeSign = gridSignAt(g, cd.eye);
        tbb::parallel_for(0, tilesX * tilesY, [&](int tile) {
            const int x0 = tile % tilesX * kTile, y0 = tile / tilesX * kTile;
            const int x1 = std::min(x0 + kTile, cd.width), y1 = std::min(y0 + kTile, cd.height);
            Ray rays[kTile * kTile];
            float t0[kTile * kTile] = {}, t1[kTile * kTile] = {};
            GridTraceResult hits[kTile * kTile];
            int n = 0;
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x, ++n) {
                    rays[n] = cam.pixelRay(x, y);
                    minMax.range(x, y, t0[n], t1[n]);
                }
            traceGridRays(g, rays, t0, t1, n, options, hits, eyeSign);
            n = 0;
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x, ++n)
                    if (hits[n].hit) {
                        const Vec3 nml = gridHitNormal(g, hits[n], rays[n].at(hits[n].t),
                                                       GridNormal::AnalyticTrilinear);
                        image[static_cast<size_t>(y) * cd.width + x] =
                            headlight(nml, rays[n].direction);
                    }
        });
    });
}

// Pixels where two hit masks disagree, not counting those next to a silhouette of `b`.
long mismatches(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b, int w, int h) {
    long n = 0;
    for (int y = 1; y < h - 1; ++y)
        for (int x = 1; x < w - 1; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            bool edge = false;
            for (long d : {-1L, 1L, -long(w), long(w)}) edge |= b[i] != b[i + d];
            n += !edge && a[i] != b[i];
        }
    return n;
}

// The hit mask of a depth PFM written by sdftrace (rows bottom to top).
std::vector<uint8_t> hitsFromDepthPfm(const std::string& path, int w, int h) {
    std::ifstream in(path, std::ios::binary);
    std::string kind;
    int pw, ph;
    float scale;
    in >> kind >> pw >> ph >> scale;
    in.get();
    std::vector<float> d(static_cast<size_t>(pw) * ph);
    in.read(reinterpret_cast<char*>(d.data()), d.size() * sizeof(float));
    std::vector<uint8_t> hits(static_cast<size_t>(w) * h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            hits[static_cast<size_t>(y) * w + x] =
                std::isfinite(d[static_cast<size_t>(h - 1 - y) * w + x]);
    return hits;
}

std::string fmt(const char* f, double v) {
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return b;
}

std::string vec(Vec3 v) {
    char b[128];
    std::snprintf(b, sizeof b, "%.9g,%.9g,%.9g", v.x, v.y, v.z);
    return b;
}

// The cameras for the level set `grid`: framed, close, grazing and far.
std::vector<std::pair<std::string, CameraDesc>> cameras(const Grid& grid, int size) {
    const Bounds3 b = grid.surfaceBounds();
    const CameraDesc framed = frameBounds(b, 35.0f, size, size);
    // Close-up: from a point on the way to the framed eye, a tenth of the object's size above the
    // surface where the central ray meets it; the surface fills the frame.
    CameraDesc close = framed;
    {
        // The hit nearest the image centre (the central ray may pass through a hole or a handle).
        const GridView v = grid.view();
        const Camera cam(framed);
        float best = INFINITY;
        Ray bestRay = cam.pixelRay(size / 2, size / 2);
        Vec3 p = framed.target;
        for (int y = 0; y <= 16; ++y)
            for (int x = 0; x <= 16; ++x) {
                const float px = size * (0.25f + 0.5f * x / 16),
                            py = size * (0.25f + 0.5f * y / 16);
                const Ray r = cam.rayThrough(px, py);
                const GridTraceResult hit = traceGridRay(v, r, 0, 1e30f, GridTraceOptions{});
                const float d = std::hypot(px - 0.5f * size, py - 0.5f * size);
                if (hit.hit && d < best) {
                    best = d;
                    bestRay = r;
                    p = r.at(hit.t);
                }
            }
        close.target = p;
        close.eye = p - bestRay.direction * (0.12f * length(b.extent()));
    }
    // Grazing: level with a plane a tenth below the object's top, from far to the side, so the
    // rays skim the upper surface at shallow angles.
    CameraDesc grazing = framed;
    {
        const Vec3 c = b.center();
        const float y = b.hi.y - 0.1f * b.extent().y;
        grazing.target = {c.x, y, c.z};
        grazing.eye =
            grazing.target + normalize(Vec3(1.0f, 0.02f, 0.35f)) * (1.6f * length(b.extent()));
        grazing.fovDeg = 25;
    }
    // Far: the framed view from four times as far, the object a quarter as wide on the image.
    CameraDesc far = framed;
    far.eye = framed.target + (framed.eye - framed.target) * 4.0f;
    return {{"framed", framed}, {"close", close}, {"grazing", grazing}, {"far", far}};
}

void runMesh(const std::string& path, const Options& o) {
    const std::string name = std::filesystem::path(path).stem().string();
    auto t0 = Clock::now();
    const TriangleMesh mesh = loadMesh(path);
    const double loadMs = ms(t0, Clock::now());

    // The level set, through a file.
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> tris;
    for (const Vec3& p : mesh.positions) points.emplace_back(p.x, p.y, p.z);
    for (const auto& t : mesh.triangles) tris.emplace_back(t[0], t[1], t[2]);
    const Bounds3 mb = mesh.bounds();
    const double voxel = maxComponent(mb.extent()) / o.res;
    auto xf = openvdb::math::Transform::createLinearTransform(voxel);
    t0 = Clock::now();
    openvdb::FloatGrid::Ptr made =
        openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xf, points, tris, 3.0f);
    const double bakeMs = ms(t0, Clock::now());
    made->setName("surface");
    const std::string vdbPath =
        "/tmp/sdftrace-scale-" + name + "-" + std::to_string(o.res) + ".vdb";
    openvdb::io::File(vdbPath).write({made});
    made.reset();

    // Import against OpenVDB's read.
    std::vector<double> ours, theirs;
    Grid grid;
    openvdb::FloatGrid::Ptr vdb;
    for (int r = 0; r < o.reps; ++r) {
        t0 = Clock::now();
        grid = loadVdb(vdbPath);
        ours.push_back(ms(t0, Clock::now()));
        t0 = Clock::now();
        openvdb::io::File f(vdbPath);
        f.open(false);  // no delayed loading: the whole grid read now
        vdb = openvdb::gridPtrCast<openvdb::FloatGrid>(f.readGrid("surface"));
        f.close();
        theirs.push_back(ms(t0, Clock::now()));
    }
    const double importMs = median(ours), vdbReadMs = median(theirs);
    std::printf(
        "\n### %s: %zu triangles, level set at %d cells (%zu active voxels)\n\n"
        "mesh load %.0f ms; meshToLevelSet %.0f ms; .vdb %.1f MiB; import: sdftrace %.0f ms, "
        "OpenVDB read %.0f ms (%.2fx); memory: sdftrace sparse grid %.1f MiB (block %d), "
        "OpenVDB memUsage %.1f MiB (%.2fx)\n\n",
        name.c_str(), mesh.triangles.size(), o.res, size_t(vdb->activeVoxelCount()), loadMs, bakeMs,
        std::filesystem::file_size(vdbPath) / 1048576.0, importMs, vdbReadMs, vdbReadMs / importMs,
        grid.memoryBytes() / 1048576.0, grid.blockSize(), vdb->memUsage() / 1048576.0,
        double(vdb->memUsage()) / grid.memoryBytes());
    std::printf(
        "| camera | size | sdftrace render | OpenVDB render | ratio | Embree | vs Embree | "
        "sdftrace rays | vs Embree | smooth | ratio | sdftrace process | OpenVDB program | ratio | "
        "hits | hit mismatches | DDA steps / tests per pixel |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    std::fflush(stdout);

    const EmbreeScene embree(mesh);
    for (int size : o.sizes)
        for (const auto& [camName, cd] : cameras(grid, size)) {
            const std::string smoothCmd =
                std::string(SDFT_CLI_PATH) + " render " + vdbPath + " --no-shadows -q --threads " +
                std::to_string(o.threads) + " --width " + std::to_string(size) + " --height " +
                std::to_string(size) + " --eye " + vec(cd.eye) + " --target " + vec(cd.target) +
                " --up " + vec(cd.up) + " --fov " + fmt("%.9g", cd.fovDeg);
            const std::string cmd = smoothCmd + " --grid-normals analytic";
            const std::string vdbCmd = std::string(SDFT_OPENVDB_RENDER_PATH) + " " + vdbPath + " " +
                                       vec(cd.eye) + " " + vec(cd.target) + " " + vec(cd.up) + " " +
                                       fmt("%.9g", cd.fovDeg) + " " + std::to_string(size) + " " +
                                       std::to_string(size) + " " + std::to_string(o.threads) +
                                       " /tmp/sdftrace-scale-bench.ppm";
            if (o.commands)
                std::fprintf(stderr, "%s %d²: %s\n", camName.c_str(), size, cmd.c_str());
            std::vector<double> phase, smoothPhase, wall, vdbRender, vdbWhole, embreeMs, raysMs;
            float travSteps = 0, isectTests = 0, hitPercent = 0;
            std::vector<float> image;
            std::vector<uint8_t> vdbMask;
            for (int r = 0; r < o.reps; ++r) {
                double w = 0;
                const std::string err = runProcess(cmd + " -o /tmp/sdftrace-scale-bench.png", w);
                const size_t at = err.find(" in ");
                phase.push_back(1000.0 * std::atof(err.c_str() + at + 4));
                const size_t hitsAt = err.rfind("% hits");
                if (hitsAt != std::string::npos) {
                    const size_t from = err.rfind(' ', hitsAt);
                    hitPercent = std::strtof(err.c_str() + from + 1, nullptr);
                }
                const size_t dda = err.find("DDA: ");
                if (dda != std::string::npos)
                    std::sscanf(err.c_str() + dda,
                                "DDA: %f traversal steps and %f intersection tests", &travSteps,
                                &isectTests);
                wall.push_back(w);
                const std::string smoothErr =
                    runProcess(smoothCmd + " -o /tmp/sdftrace-scale-bench.png", w);
                smoothPhase.push_back(1000.0 *
                                      std::atof(smoothErr.c_str() + smoothErr.find(" in ") + 4));
                double vw = 0;
                runProcess(vdbCmd, vw);
                vdbWhole.push_back(vw);
                t0 = Clock::now();
                vdbMask = renderOpenVdb(*vdb, cd, o.threads, image);
                vdbRender.push_back(ms(t0, Clock::now()));
                t0 = Clock::now();
                renderEmbree(embree, cd, o.threads, image);
                embreeMs.push_back(ms(t0, Clock::now()));
                t0 = Clock::now();
                renderGridRays(grid, cd, o.threads, image);
                raysMs.push_back(ms(t0, Clock::now()));
            }
            double w = 0;
            runProcess(
                cmd + " -o /tmp/sdftrace-scale-bench.png --aov depth=/tmp/sdftrace-scale-depth.pfm",
                w);
            const long bad = mismatches(
                hitsFromDepthPfm("/tmp/sdftrace-scale-depth.pfm", size, size), vdbMask, size, size);
            const double p = median(phase), vr = median(vdbRender), e = median(embreeMs),
                         pw = median(wall), vw = median(vdbWhole), ps = median(smoothPhase),
                         gr = median(raysMs);
            std::printf(
                "| %s | %d² | %.1f ms | %.1f ms | %.2fx | %.1f ms | %.2fx | %.1f ms | %.2fx | %.1f "
                "ms | "
                "%.2fx | %.0f ms | %.0f ms | %.2fx | %.0f%% | %ld | %.1f / %.2f |\n",
                camName.c_str(), size, p, vr, vr / p, e, p / e, gr, gr / e, ps, vr / ps, pw, vw,
                vw / pw, hitPercent, bad, travSteps, isectTests);
            std::fflush(stdout);
        }
    if (!o.keep) std::remove(vdbPath.c_str());
}

constexpr const char* kUsage =
    "usage: sdftrace_scale_bench [--res 256] [--sizes 512,1024] [--reps 5] [--threads 2] [--keep]\n"
    "                            [--commands] mesh.obj|ply ...\n";

int run(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "%s needs a value\n", a.c_str());
                std::exit(2);
            }
            return argv[++i];
        };
        if (a == "--res")
            o.res = bench::intFlag(a, next(), 8);
        else if (a == "--reps")
            o.reps = bench::intFlag(a, next());
        else if (a == "--threads")
            o.threads = bench::intFlag(a, next());
        else if (a == "--keep")
            o.keep = true;
        else if (a == "--commands")
            o.commands = true;
        else if (a == "--sizes")
            o.sizes = bench::intListFlag(a, next(), 16);
        else if (a == "--help" || a == "-h") {
            std::fputs(kUsage, stdout);
            return 0;
        } else if (a.rfind("--", 0) == 0) {
            std::fprintf(stderr, "%s: unknown option\n%s", a.c_str(), kUsage);
            return 2;
        } else
            o.meshes.push_back(a);
    }
    if (o.meshes.empty()) {
        for (const char* m : {"bunny_npm.obj", "stanford-bunny.obj", "teapot.obj"})
            o.meshes.push_back(std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + m);
    }
    openvdb::initialize();
    std::printf("## sdftrace vs OpenVDB and Embree: %d threads, medians of %d runs\n", o.threads,
                o.reps);
    for (const std::string& m : o.meshes) runMesh(m, o);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const std::exception& e) {
        // A mesh that does not load (bad flags exit in bench_flags.h).
        std::fprintf(stderr, "sdftrace_scale_bench: %s\n", e.what());
        return 1;
    }
}
