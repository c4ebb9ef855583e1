// The bakers' row-batched CPU passes against their per-vertex forms in one process, each result
// compared bit for bit on every run: jump flooding (the row sweep, jump_flood.cpp, against
// jumpFloodVertex per vertex, the GPU's body), winding-number signs (winding_packet.h against
// WindingNumber::inside per vertex) and RTSDF's coarse lookups (interpolateDenseRow against
// GridView::interpolate per vertex), and RTSDF's per-frame block grid (refreshed against
// sparsified afresh). TBB over z slabs on every hardware thread; medians of --runs.
// SDFT_SIMD=sse2 measures the baseline build of the dispatched rows.
//
//   sdftrace_bake_rows_bench [--runs 5] [--meshes bunny_npm:127,teapot:127,stanford-bunny:255]
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "sdftrace/bake/jump_flood.h"
#include "sdftrace/bake/jump_flood_step.h"
#include "sdftrace/bake/rtsdf_bake.h"
#include "sdftrace/bake/rtsdf_vertex.h"
#include "sdftrace/bake/surface_seeds.h"
#include "sdftrace/bake/winding_number.h"
#include "sdftrace/bake/winding_packet.h"
#include "sdftrace/exec/simd.h"
#include "sdftrace/field/grid.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/io/mesh_io.h"

using namespace sdft;

namespace {

using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

double msSince(Clock::time_point t) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

// Runs rows() and perVertex() `runs` times each, checks equal() after each pair and prints a row.
template <class Rows, class PerVertex, class Equal>
void compare(const char* what, const std::string& mesh, int cells, size_t vertices, int runs,
             Rows&& rows, PerVertex&& perVertex, Equal&& equal) {
    std::vector<double> a, b;
    bool same = true;
    for (int r = 0; r < runs; ++r) {
        auto t = Clock::now();
        rows();
        a.push_back(msSince(t));
        t = Clock::now();
        perVertex();
        b.push_back(msSince(t));
        same = same && equal();
    }
    std::printf("| %s | %s, %d cells (%zu vertices) | %.1f | %.1f | %.2fx | %s |\n", what,
                mesh.c_str(), cells, vertices, median(b), median(a), median(b) / median(a),
                same ? "yes" : "NO");
    std::fflush(stdout);
}

void meshRows(const std::string& name, int cells, int runs) {
    const TriangleMesh mesh =
        loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + name + ".obj");
    SampleOptions so;
    so.resolution = cells;
    so.kind = GridKind::Dense;
    const GridShape s = gridShapeFor(mesh.bounds(), so);
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    const size_t n = s.vertexCount();

    // Jump flooding of the voxelized surface, every pass.
    const SurfaceSeeds seeds = seedSurfaceVertices(mesh, s);
    std::vector<Vec3> rowsOut, ref;
    compare(
        "jump flooding (all passes)", name, cells, n, runs,
        [&] { rowsOut = jumpFlood(s, seeds.point, JfaVariant::Plain); },
        [&] {
            std::vector<Vec3> seed = seeds.point, next(n);
            for (int off : jumpFloodOffsets(s, JfaVariant::Plain)) {
                tbb::parallel_for(0, vz, [&](int k) {
                    for (int j = 0; j < vy; ++j)
                        for (int i = 0; i < vx; ++i)
                            next[vertexIndex(s, i, j, k)] =
                                jumpFloodVertex(s, seed.data(), i, j, k, off);
                });
                seed.swap(next);
            }
            ref = std::move(seed);
        },
        [&] { return std::memcmp(rowsOut.data(), ref.data(), n * sizeof(Vec3)) == 0; });

    // Winding-number signs at every vertex.
    const WindingNumber winding(mesh);
    std::vector<uint8_t> packet(n), scalar(n);
    compare(
        "winding signs", name, cells, n, runs,
        [&] {
            tbb::parallel_for(0, vz, [&](int k) {
                std::vector<Vec3> points(static_cast<size_t>(vx));
                for (int j = 0; j < vy; ++j) {
                    for (int i = 0; i < vx; ++i) points[i] = vertexPosition(s, i, j, k);
                    windingInsideRow(winding.view(), points.data(), vx, winding.beta(),
                                     packet.data() + vertexIndex(s, 0, j, k));
                }
            });
        },
        [&] {
            tbb::parallel_for(0, vz, [&](int k) {
                for (int j = 0; j < vy; ++j)
                    for (int i = 0; i < vx; ++i)
                        scalar[vertexIndex(s, i, j, k)] =
                            winding.inside(vertexPosition(s, i, j, k));
            });
        },
        [&] { return packet == scalar; });
}

// RTSDF's fine pass reading its half-resolution coarse field at every fine vertex.
void coarseRows(int cells, int runs) {
    GridShape s;
    for (int a = 0; a < 3; ++a) s.cells[a] = cells;
    s.voxelSize = 1.0f / static_cast<float>(cells);
    s.origin = Vec3(-0.5f);
    const GridShape c = rtsdfCoarseShape(s);
    std::vector<float> samples(c.vertexCount());
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(-1, 1);
    for (float& v : samples) v = u(rng);
    GridView cv;
    cv.kind = GridKind::Dense;
    cv.shape = c;
    cv.samples = samples.data();
    const size_t n = s.vertexCount();
    std::vector<float> rows(n), ref(n);
    compare(
        "RTSDF coarse lookups", "random field", cells, n, runs,
        [&] {
            tbb::parallel_for(0, s.vertices(2), [&](int k) {
                for (int j = 0; j < s.vertices(1); ++j)
                    interpolateDenseRow(cv, s, j, k, rows.data() + vertexIndex(s, 0, j, k));
            });
        },
        [&] {
            tbb::parallel_for(0, s.vertices(2), [&](int k) {
                for (int j = 0; j < s.vertices(1); ++j)
                    for (int i = 0; i < s.vertices(0); ++i)
                        ref[vertexIndex(s, i, j, k)] = cv.interpolate(vertexPosition(s, i, j, k));
            });
        },
        [&] { return std::memcmp(rows.data(), ref.data(), n * sizeof(float)) == 0; });
}

// RTSDF's per-frame grid (every block kept, bandVoxels 1e6): sparsified afresh from the frame's
// dense samples as before (Grid::sparseFromDense) against the last frame's complete grid refreshed
// (Grid::refreshComplete); every vertex compared bit for bit on every run.
void gridFinish(int cells, int runs) {
    GridShape s;
    for (int a = 0; a < 3; ++a) s.cells[a] = cells;
    s.voxelSize = 1.0f / static_cast<float>(cells);
    s.origin = Vec3(-0.5f);
    auto field = [&](float shift) {
        std::vector<float> f(s.vertexCount());
        tbb::parallel_for(0, s.vertices(2), [&](int k) {
            for (int j = 0; j < s.vertices(1); ++j)
                for (int i = 0; i < s.vertices(0); ++i) {
                    const Vec3 p = vertexPosition(s, i, j, k);
                    f[vertexIndex(s, i, j, k)] =
                        length(p - Vec3(shift, 0, 0)) - 0.3f +
                        0.02f * std::sin(40 * p.x) * std::sin(30 * p.y) * std::sin(35 * p.z);
                }
        });
        return f;
    };
    const Grid last = Grid::completeFromDense(s, field(0), 4, 1e6f);
    const std::vector<float> now = field(0.05f);
    std::vector<double> a, b;
    bool same = true;
    for (int r = 0; r < runs; ++r) {
        auto t = Clock::now();
        const Grid refreshed = last.refreshComplete(now);
        a.push_back(msSince(t));
        t = Clock::now();
        const Grid sparse = Grid::sparseFromDense(s, now, 4, 1e6f);
        b.push_back(msSince(t));
        same = same && refreshed.vertexSamples() == sparse.vertexSamples() &&
               refreshed.lipschitz() == sparse.lipschitz() &&
               refreshed.tileSkip() == sparse.tileSkip();
    }
    std::printf("| %d cells (%zu vertices) | %.1f | %.1f | %.2fx | %s |\n", cells, s.vertexCount(),
                median(b), median(a), median(b) / median(a), same ? "yes" : "NO");
    std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
    int runs = 5;
    std::string meshes = "bunny_npm:127,teapot:127,elephant-with-holes:96,stanford-bunny:255";
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--runs" && i + 1 < argc) {
            runs = std::max(1, std::atoi(argv[++i]));
        } else if (a == "--meshes" && i + 1 < argc) {
            meshes = argv[++i];
        } else {
            std::fprintf(stderr,
                         "usage: sdftrace_bake_rows_bench [--runs N] [--meshes name:cells,...]\n");
            return 2;
        }
    }
    std::printf("SIMD: %s\n\n", simdLevelName(simdLevel()));
    std::printf(
        "| pass | grid | per vertex ms | rows ms | speedup | same bits |\n| --- | --- | --- | --- "
        "| --- | --- |\n");
    std::stringstream list(meshes);
    for (std::string item; std::getline(list, item, ',');) {
        const size_t colon = item.find(':');
        meshRows(item.substr(0, colon),
                 colon == std::string::npos ? 127 : std::atoi(item.c_str() + colon + 1), runs);
    }
    coarseRows(256, runs);
    coarseRows(512, runs);
    std::printf(
        "\nRTSDF's per-frame grid (every block kept):\n\n| grid | sparsify afresh ms | "
        "refresh ms | speedup | same vertices |\n| --- | --- | --- | --- | --- |\n");
    for (int cells : {128, 256, 512}) gridFinish(cells, runs);
    return 0;
}
