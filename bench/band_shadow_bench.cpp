// SDF soft shadows of meshes baked in a scene as narrow bands, against a complete SDF and the
// truth: does what a narrow-band grid reads beyond its band (gridDistanceBound) depend on the
// band's width? Each mesh stands on a floor under a sun 3 degrees wide, scaled to 1 unit; primary
// rays hit its triangles (primary_triangles, RTSDF's hybrid mode), so every row shades the same
// points and only the shadows differ. Rows: the sparse bake at the default band (3 voxels), at
// band 12, the dense bake (every sample exact) with SDF soft shadows (RTSDF k h / t, Aaltonen's
// triangulation), and the default band with 16 distributed rays (the grid's own error). Truth:
// shadow rays on the triangles themselves (Embree; --truth per point over the sun's disk).
// Per row and camera: the shadow AOV's RMSE against the truth over the shadowed pixels (the truth
// or any row below 0.99: one set for all rows) of the floor and of the mesh, the shadow marches'
// field evaluations per pixel, and the render's median time.
//
//   build/release/bench/sdftrace_band_shadow_bench [--resolution 128 --truth 256 --width 320
//       --height 200 --reps 3 --images DIR] mesh.obj...
// --images writes each row's picture and shadow AOV as PNGs into DIR. Arguments that are grid files
// (.sdfg, .vdb) instead time Grid::computeGapLattice on them (what a scene adds to loading them):
// median of --reps, with the lattice's step and bytes against the grid's.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/io/grid_file.h"
#include "sdftrace/io/image_io.h"
#include "sdftrace/io/mesh_io.h"
#include "sdftrace/math/sampling.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"
#include "sdftrace/scene/prepare_scene.h"

using namespace sdft;

namespace {

using Clock = std::chrono::steady_clock;

struct Row {
    std::string name, mesh, render;
    bool gapLattice = true;
};

struct View {
    const char* name;
    const char* eye;
};

// The mesh scaled to 1 unit along its longest side, its base on the floor at the origin: the
// scene keys, and the placed mesh.
struct Placement {
    std::string keys;
    TriangleMesh mesh;
};

Placement placement(const std::string& path) {
    Placement out{"", loadMesh(path)};
    const Bounds3 b = out.mesh.bounds();
    const Vec3 e = b.extent();
    const float s = 1.0f / std::max(e.x, std::max(e.y, e.z));
    const Vec3 c = b.center(), t(-c.x * s, -b.lo.y * s, -c.z * s);
    char text[256];
    std::snprintf(text, sizeof text, R"("scale": %.9g, "translate": [%.9g, %.9g, %.9g])", s, t.x,
                  t.y, t.z);
    out.keys = text;
    for (Vec3& p : out.mesh.positions) p = p * s + t;
    return out;
}

// The truth on the triangles: per pixel that hit something, the share of `rays` shadow rays
// towards the sun's disk (Embree, from the hit point nudged along its normal) that miss the mesh.
// The floor shadows nothing the camera sees. Pixels that hit nothing read 1.
std::vector<float> triangleTruth(const Film& film, const CameraDesc& desc, const MeshBvh& bvh,
                                 int rays) {
    const Camera camera(desc);
    const Vec3 toSun = normalize(Vec3(0.6f, 1.0f, 0.4f));
    const float cosMax = std::cos(radians(1.5f));
    std::vector<float> out(film.pixels(), 1.0f);
    tbb::parallel_for(size_t(0), film.pixels(), [&](size_t i) {
        if (!std::isfinite(film.depth[i])) return;
        const int x = static_cast<int>(i % static_cast<size_t>(film.width));
        const int y = static_cast<int>(i / static_cast<size_t>(film.width));
        const Ray primary = camera.pixelRay(x, y);
        const Vec3 n(film.normal[3 * i], film.normal[3 * i + 1], film.normal[3 * i + 2]);
        const Vec3 p = primary.at(film.depth[i]) + n * 1e-3f;
        int lit = 0;
        for (int k = 0; k < rays; ++k) {
            // A stratified, per-pixel rotated set over the disk.
            const float u1 = (static_cast<float>(k) + 0.5f) / static_cast<float>(rays);
            const float u2 = std::fmod(
                static_cast<float>(k) * 0.618034f + static_cast<float>(i % 977) * 0.1234567f, 1.0f);
            const Vec3 d = sampleCone(toSun, cosMax, u1, u2);
            lit += !std::isfinite(bvh.firstHit({p, d}, 0.0f).t);
        }
        out[i] = static_cast<float>(lit) / static_cast<float>(rays);
    });
    return out;
}

std::string sceneText(const View& view, int width, int height, const std::string& mesh,
                      const std::string& render) {
    return std::string(R"({"camera": {"eye": )") + view.eye +
           R"(, "target": [0.3, 0.3, 0.2], "fov": 40, "width": )" + std::to_string(width) +
           R"(, "height": )" + std::to_string(height) + R"(},
      "ambient": [0.1, 0.1, 0.1],
      "lights": [{"type": "directional", "direction": [-0.6, -1, -0.4], "angle": 3, "intensity": 2}],
      "objects": [
        {"type": "box", "size": [6, 0.2, 6], "translate": [0, -0.1, 0]},
        )" +
           mesh +
           R"(],
      "render": {"primary_triangles": true, )" +
           render + "}}";
}

// RMSE of a shadow AOV against the truth's over one set of pixels for every row: those of the
// floor (normal straight up) or of the mesh where the truth or any row is below 0.99.
double rmse(const std::vector<float>& shadow, const Film& truth, const std::vector<Film>& rows,
            bool floor) {
    double sq = 0;
    size_t n = 0;
    for (size_t i = 0; i < shadow.size(); ++i) {
        if ((truth.normal[3 * i + 1] > 0.9999f) != floor) continue;
        bool shadowed = truth.shadow[i] < 0.99f;
        for (const Film& f : rows) shadowed = shadowed || f.shadow[i] < 0.99f;
        if (!shadowed) continue;
        sq += (double(shadow[i]) - truth.shadow[i]) * (double(shadow[i]) - truth.shadow[i]);
        ++n;
    }
    return n ? std::sqrt(sq / static_cast<double>(n)) : 0;
}

// What the gap lattice costs on a grid file: time, step and bytes.
void latticeCost(const std::string& path, int reps) {
    Grid grid = loadGridFile(path);
    std::vector<double> times;
    for (int k = 0; k < reps; ++k) {
        const auto t0 = Clock::now();
        grid.computeGapLattice();
        times.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    }
    std::sort(times.begin(), times.end());
    const GridShape& s = grid.shape();
    std::printf(
        "%s: %dx%dx%d cells, grid %.1f MiB; gap lattice step %d, %.2f MiB, %.1f ms (median of "
        "%d)\n",
        path.c_str(), s.cells[0], s.cells[1], s.cells[2],
        static_cast<double>(grid.memoryBytes() - grid.gapLattice().size()) / (1 << 20),
        grid.gapStep(), static_cast<double>(grid.gapLattice().size()) / (1 << 20),
        1e3 * times[times.size() / 2], reps);
}

struct Options {
    int resolution = 128, truthRays = 256, width = 320, height = 200, reps = 3;
    std::string images;  // where each row's pictures go; empty: none
};

// One mesh and camera: every row's shadows against the truth, a table line each.
void benchView(const Options& o, const std::string& path, const Placement& place,
               const MeshBvh& bvh, const View& view, const std::vector<Row>& rows) {
    const int width = o.width, height = o.height, reps = o.reps, truthRays = o.truthRays;
    const std::string& images = o.images;
    const std::string name = path.substr(path.find_last_of('/') + 1);
    double evaluations = 0;  // shadow evaluations per pixel of the last render
    auto shadowOf = [&](const Row& r, double* ms) {
        const std::string mesh =
            R"({"mesh": ")" + path + R"(", )" + r.mesh + ", " + place.keys + "}";
        Scene s = describeSceneText(sceneText(view, width, height, mesh, r.render), name);
        PrepareOptions prepare;
        prepare.gapLattice = r.gapLattice;
        prepareScene(s, prepare);
        const RenderPlan plan = planRender(s);
        std::vector<double> times;
        Film film(plan.camera.width, plan.camera.height);
        for (int k = 0; k < (ms ? reps : 1); ++k) {
            film = Film(plan.camera.width, plan.camera.height);
            const auto t0 = Clock::now();
            const RenderStats st = render(plan, film);
            evaluations =
                static_cast<double>(st.shadowEvaluations) / static_cast<double>(film.pixels());
            times.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
        }
        std::sort(times.begin(), times.end());
        if (ms) *ms = 1e3 * times[times.size() / 2];
        if (!ms) film.shadow = triangleTruth(film, plan.camera, bvh, truthRays);
        return film;
    };
    // Every row shades the same points: the first row's, with the truth's shadows.
    const Film reference = shadowOf(rows.front(), nullptr);
    std::vector<Film> films;
    std::vector<double> times, perPixel;
    for (const Row& r : rows) {
        double ms = 0;
        films.push_back(shadowOf(r, &ms));
        times.push_back(ms);
        perPixel.push_back(evaluations);
        if (!images.empty()) {
            const Film& f = films.back();
            const std::string stem =
                images + "/" + name + "-" + view.name + "-" + std::to_string(&r - rows.data());
            writePng(stem + ".png", f.width, f.height, 3, toneMapSrgb(f.color));
            writeAov(f, Aov::Shadow, stem + "-shadow.png");
        }
    }
    for (size_t r = 0; r < rows.size(); ++r) {
        std::printf("| %s | %s | %s | %.4f | %.4f | %.1f | %.1f ms |\n", name.c_str(), view.name,
                    rows[r].name.c_str(), rmse(films[r].shadow, reference, films, true),
                    rmse(films[r].shadow, reference, films, false), perPixel[r], times[r]);
        std::fflush(stdout);
    }
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    std::vector<std::string> meshes;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        int* target = a == "--resolution" ? &o.resolution
                      : a == "--truth"    ? &o.truthRays
                      : a == "--width"    ? &o.width
                      : a == "--height"   ? &o.height
                      : a == "--reps"     ? &o.reps
                                          : nullptr;
        if (a == "--images" && i + 1 < argc) {
            o.images = argv[++i];
        } else if (target && i + 1 < argc) {
            *target = std::max(1, std::atoi(argv[++i]));
        } else if (a.rfind("--", 0) == 0) {
            std::fprintf(stderr, "unknown option %s\n", a.c_str());
            return 2;
        } else {
            meshes.push_back(a);
        }
    }
    if (meshes.empty()) {
        std::fprintf(stderr, "usage: sdftrace_band_shadow_bench [options] mesh...\n");
        return 2;
    }
    const std::string soft = R"("shadow_method": "soft")";
    const std::string res = "\"resolution\": " + std::to_string(o.resolution);
    const std::vector<Row> rows = {
        {"band 3 (default), soft, without the gap lattice", res, soft, false},
        {"band 3 (default), soft", res, soft},
        {"band 12, soft", res + R"(, "band": 12)", soft},
        {"dense (complete SDF), soft", res + R"(, "dense": true)", soft},
        {"band 3, distributed 16 rays", res,
         R"("shadow_method": "distributed", "shadow_rays": 16)"},
    };
    const std::vector<View> views = {
        {"near", "[1.3, 1.3, 2.0]"}, {"far", "[3.5, 4.0, 6.0]"}, {"grazing", "[2.6, 0.25, 1.6]"}};
    std::printf(
        "## SDF soft shadows of meshes at %d cells against the truth (%dx%d; truth: %d shadow "
        "rays per point on the triangles)\n\n| mesh | camera | row | RMSE, floor | RMSE, mesh | "
        "shadow evaluations per pixel | render (median of %d) |\n"
        "| --- | --- | --- | --- | --- | --- | --- |\n",
        o.resolution, o.width, o.height, o.truthRays, o.reps);
    for (const std::string& path : meshes) {
        if (isGridFile(path)) {
            latticeCost(path, o.reps);
            continue;
        }
        const Placement place = placement(path);
        const MeshBvh bvh(place.mesh);
        for (const View& view : views) benchView(o, path, place, bvh, view, rows);
    }
    return 0;
}
