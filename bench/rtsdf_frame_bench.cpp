// RTSDF's per-frame pipeline on the CPU (issue 16; Tan et al. 2022, Tables 1 and 3, figs. 5-6): a
// mesh moving on a circle (as fig. 5's teapot; the closed bunny by default), its SDF regenerated
// every frame over a fixed region: the coarse SDF by voxelization + jump flooding at half the
// resolution, then x rays per vertex within the mask d of it (the fine SDF), accumulated by eq. 1
// with decay alpha. Per size (RTSDF's S: 128 fine over 64 coarse, M: 256 over 128) and x: the
// passes' times per frame (medians over the frames after the first), and the last frame's accuracy
// in the mask against the exact SDF of that frame's geometry (mean and max |error| in fine voxels,
// wrong signs), and the ghosting: the mean amount by which the field underestimates the distance on
// the vertices the surface left in the last 10 frames (exact distance now more than a voxel above
// what it was 10 frames ago). With several decays (--alphas), the accuracy and ghosting against
// alpha and x (RTSDF figs. 5-6: more history converges further and ghosts longer).
//
// usage: sdftrace_rtsdf_frame_bench [--mesh file] [--frames N] [--sizes 128,256] [--rays 1,5,10]
//                                   [--alphas 0.95] [--degrees 6] [--threads T]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench_flags.h"
#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/bake/rtsdf_bake.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/io/mesh_io.h"

using namespace sdft;

namespace {

using Clock = std::chrono::steady_clock;
double seconds(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
}

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

// The mesh moved to frame k of a circle, `degrees` per frame (0: it stands still), radius r, in
// the xz plane.
TriangleMesh atFrame(const TriangleMesh& mesh, int k, float degrees, float r) {
    TriangleMesh m = mesh;
    const float a = static_cast<float>(M_PI) / 180 * degrees * static_cast<float>(k);
    const Vec3 offset(r * std::cos(a), 0, r * std::sin(a));
    for (Vec3& p : m.positions) p = p + offset;
    return m;
}

// The exact signed distances of `mesh` at the vertices of `shape` (the narrow band's exact bake,
// dense: every vertex).
std::vector<float> exactSamples(const TriangleMesh& mesh, const GridShape& shape, int threads) {
    MeshBakeOptions o;
    o.sampling.kind = GridKind::Dense;
    o.sampling.threads = threads;
    o.shape = shape;
    return bakeMesh(mesh, o).grid.vertexSamples();
}

}  // namespace

int main(int argc, char** argv) {
    // A closed mesh: the exact SDF of an open one (the teapot) closes its holes by films
    // (decision 4), which rays through the holes do not see.
    std::string meshPath = std::string(SDFT_SOURCE_DIR) + "/data/meshes/bunny_npm.obj";
    int frames = 20, threads = 2;
    std::vector<float> alphas = {0.95f};
    float degrees = 6;
    std::vector<int> sizes = {128, 256}, rays = {1, 5, 10};
    constexpr const char* kUsage =
        "usage: sdftrace_rtsdf_frame_bench [--mesh PATH] [--frames 20] [--sizes 128,256]\n"
        "       [--rays 1,5,10] [--alphas 0.95,...] [--degrees 6] [--threads 2]\n";
    if (const int status = bench::checkFlagPairs(argc, argv, kUsage); status >= 0) return status;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string a = argv[i], v = argv[i + 1];
        if (a == "--mesh")
            meshPath = v;
        else if (a == "--frames")
            frames = bench::intFlag(a, v, 2);
        else if (a == "--sizes")
            sizes = bench::intListFlag(a, v, 8);
        else if (a == "--rays")
            rays = bench::intListFlag(a, v);
        else if (a == "--alpha" || a == "--alphas")
            alphas = bench::floatListFlag(a, v);
        else if (a == "--degrees")
            degrees = bench::floatFlag(a, v);
        else if (a == "--threads")
            threads = bench::intFlag(a, v);
        else {
            std::fprintf(stderr, "unknown option %s\n", a.c_str());
            return 2;
        }
    }
    const TriangleMesh mesh = loadMesh(meshPath);
    const Bounds3 b = mesh.bounds();
    const float radius = 0.5f * maxComponent(b.extent());
    // The region the mesh sweeps over a whole turn.
    const Bounds3 region{b.lo - Vec3(radius, 0, radius), b.hi + Vec3(radius, 0, radius)};
    std::printf(
        "## RTSDF per frame on the CPU: %s (%zu triangles) on a circle of radius %.3g, %.3g "
        "degrees per frame, %d frames, mask 3 fine voxels, %d threads\n\n",
        meshPath.c_str(), mesh.triangles.size(), radius, degrees, frames, threads);
    std::printf(
        "| fine / coarse | alpha | x | BVH build | voxelize + jump flood (coarse) | rays (fine) | "
        "frame | refined vertices | mean / max error (voxels) | wrong signs | ghost "
        "(voxels) |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (int size : sizes) {
        SampleOptions so;
        so.resolution = size;
        so.threads = threads;
        const GridShape shape = gridShapeFor(region, so);
        const float h = shape.voxelSize;
        // The exact fields of the last frame and of 10 frames before it.
        const int last = frames - 1;
        const std::vector<float> exact =
            exactSamples(atFrame(mesh, last, degrees, radius), shape, threads);
        const std::vector<float> earlier =
            exactSamples(atFrame(mesh, std::max(0, last - 10), degrees, radius), shape, threads);
        for (const float alpha : alphas)
            for (int x : rays) {
                RtsdfHistory history;
                history.alpha = alpha;
                RtsdfOptions o;
                o.rays = x;
                o.history = &history;
                std::vector<double> bvhS, coarseS, rayS, frameS;
                size_t refined = 0;
                std::vector<float> f;
                for (int k = 0; k < frames; ++k) {
                    const TriangleMesh m = atFrame(mesh, k, degrees, radius);
                    const auto t0 = Clock::now();
                    const MeshBvh bvh(m);
                    const auto t1 = Clock::now();
                    RtsdfStats st;
                    f = bakeRtsdfSamples(m, bvh, shape, o, threads, &st);
                    const auto t2 = Clock::now();
                    if (k > 0) {  // the first frame allocates the history
                        bvhS.push_back(seconds(t0, t1));
                        coarseS.push_back(st.coarseSeconds);
                        rayS.push_back(st.raySeconds);
                        frameS.push_back(seconds(t0, t2));
                    }
                    refined = st.refined;
                }
                // Accuracy in the mask of the last frame, and the ghost where the surface left.
                double sum = 0, worst = 0, ghost = 0;
                size_t n = 0, wrong = 0, left = 0;
                for (size_t i = 0; i < f.size(); ++i) {
                    if (std::fabs(exact[i]) <= 3 * h) {
                        const double e = std::fabs(f[i] - exact[i]) / h;
                        sum += e;
                        worst = std::max(worst, e);
                        wrong += (f[i] < 0) != (exact[i] < 0) && std::fabs(exact[i]) > 0.5f * h;
                        ++n;
                    }
                    if (std::fabs(exact[i]) <= 3 * h &&
                        std::fabs(exact[i]) > std::fabs(earlier[i]) + h) {
                        ghost += std::max(0.0f, std::fabs(exact[i]) - std::fabs(f[i])) / h;
                        ++left;
                    }
                }
                std::printf(
                    "| %d / %d | %.2f | %d | %.1f ms | %.1f ms | %.1f ms | %.1f ms | %zu | %.3f / "
                    "%.2f | %.3f%% | %.3f |\n",
                    size, (size + 1) / 2, alpha, x, 1e3 * median(bvhS), 1e3 * median(coarseS),
                    1e3 * median(rayS), 1e3 * median(frameS), refined, sum / n, worst,
                    100.0 * static_cast<double>(wrong) / static_cast<double>(n),
                    left ? ghost / static_cast<double>(left) : 0.0);
                std::fflush(stdout);
            }
    }
    return 0;
}
