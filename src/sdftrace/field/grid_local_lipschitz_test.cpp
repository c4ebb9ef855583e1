// Local Lipschitz bounds of sparse grids (Grid::computeLocalLipschitz) on an open mesh, the
// Stanford bunny with holes in its base: signed by the winding number, its samples flip from +d to
// -d across the surfaces that close the holes, and those few cells set the global bound.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "sdftrace/bake/exact_bake.h"
#include "sdftrace/bake/test_meshes.h"
#include "sdftrace/field/grid_distance.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/field/test_util.h"
#include "sdftrace/io/mesh_io.h"
#include "sdftrace/math/camera.h"
#include "sdftrace/trace/field_tracer.h"
#include "sdftrace/trace/grid_tracer.h"
#include "sdftrace/trace/sphere_tracer.h"

namespace sdft {
namespace {

std::shared_ptr<const Grid> openBunny() {
    static const std::shared_ptr<const Grid> grid = [] {
        const TriangleMesh mesh =
            loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/stanford-bunny.obj");
        SampleOptions o;
        o.resolution = 96;
        const GridShape shape = gridShapeFor(mesh.bounds(), o);
        return std::make_shared<const Grid>(
            bakeExactSparse(mesh, shape, 4, 3, SignMethod::WindingNumber));
    }();
    return grid;
}

// The holes' cells are steep (6 sqrt 3 from +-3 voxels), the body's are not: most surface blocks
// take the second bound, a fraction of the global one and never below 1.
TEST(GridLocalLipschitz, AnOpenMeshsBlocksKeepTheirOwnBound) {
    const GridView g = openBunny()->view();
    ASSERT_NE(g.blockLipschitz, nullptr);
    ASSERT_NE(g.tileLipschitz, nullptr);
    EXPECT_GT(g.lipschitz, 8.0f);
    EXPECT_EQ(g.lipschitzLevel[0], g.lipschitz);
    EXPECT_GE(g.lipschitzLevel[1], 1.0f);
    EXPECT_LE(g.lipschitzLevel[1], g.lipschitz / 3);
    int surface = 0, gentle = 0;
    for (size_t slot = 0; slot < openBunny()->flags().size(); ++slot) {
        if (g.blockData[slot] < 0) continue;
        ASSERT_LE(g.blockLipschitz[slot], 1);
        ++surface;
        gentle += g.blockLipschitz[slot];
    }
    std::printf("second bound %.2f (global %.2f) on %d of %d surface blocks\n", g.lipschitzLevel[1],
                g.lipschitz, gentle, surface);
    EXPECT_GT(gentle, surface * 7 / 10);
}

// A closed mesh's cells are all about as steep: one bound everywhere, as before.
TEST(GridLocalLipschitz, AClosedMeshKeepsItsGlobalBound) {
    const TriangleMesh mesh = testing::torusMesh(1, 0.35f, 48, 24);
    SampleOptions o;
    o.resolution = 64;
    const Grid grid =
        bakeExactSparse(mesh, gridShapeFor(mesh.bounds(), o), 4, 3, SignMethod::WindingNumber);
    const GridView g = grid.view();
    EXPECT_EQ(g.lipschitzLevel[1], g.lipschitz);
}

// Still a distance bound: no point of the other sign lies within |value| of a point, among
// random pairs up to 6 voxels apart over the grid's box (the nearest found: 0.26 voxel beyond).
TEST(GridLocalLipschitz, NoPointOfTheOtherSignLiesWithinTheValue) {
    const GridView g = openBunny()->view();
    const float h = g.shape.voxelSize;
    const Vec3 lo = g.shape.origin;
    const Vec3 size =
        Vec3(static_cast<float>(g.shape.cells[0]), static_cast<float>(g.shape.cells[1]),
             static_cast<float>(g.shape.cells[2])) *
        h;
    testing::Rng rng(5);
    int pairs = 0;
    float worst = -1e9f;
    for (int i = 0; i < 400000; ++i) {
        const Vec3 p = lo + Vec3(rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0, 1)) * size;
        const Vec3 q = p + rng.inCube(6.0f * h);
        const float vp = gridDistanceBound(g, p), vq = gridDistanceBound(g, q);
        if (vp == 0 || vq == 0 || (vp < 0) == (vq < 0)) continue;
        ++pairs;
        worst = std::max(worst, (std::fabs(vp) - length(p - q)) / h);
    }
    std::printf(
        "%d pairs of opposite signs; |value| exceeds their distance by at most %.3f "
        "voxels\n",
        pairs, worst);
    EXPECT_GT(pairs, 1000);
    EXPECT_LE(worst, 0.0f) << "in voxels";
}

// Sphere tracing with the grid's value as the field, the view's local bounds or (without them)
// the global one.
TraceResult sphereTraceGrid(const GridView& g, const Ray& ray, const TraceOptions& o) {
    SphereTraceState s;
    const Vec3 hi = g.shape.origin + Vec3(static_cast<float>(g.shape.cells[0]),
                                          static_cast<float>(g.shape.cells[1]),
                                          static_cast<float>(g.shape.cells[2])) *
                                         g.shape.voxelSize;
    sphereTraceBegin(s, ray, 0, 10, Bounds3{g.shape.origin, hi}, o);
    while (!s.done()) sphereTraceAdvance(s, gridDistanceBound(g, s.queryPoint()), 1.0f, o);
    return s.result;
}

// Sphere tracing the grid finds the surfaces the DDA finds, from three sides at 128^2 with
// Keinert's screen-space selection (§3.2), off the DDA image's silhouettes. With the global bound
// (10.4) the field reads a tenth of the distance, and the selection takes band and non-surface
// blocks for surfaces.
TEST(GridLocalLipschitz, SphereTracingAnOpenMeshAgreesWithTheDda) {
    const std::shared_ptr<const Grid> grid = openBunny();
    const GridView g = grid->view();
    GridView global = g;
    global.tileLipschitz = global.blockLipschitz = nullptr;
    const Tape tape = compileTape(node::grid(grid));
    const Vec3 centre = g.shape.origin + Vec3(static_cast<float>(g.shape.cells[0]),
                                              static_cast<float>(g.shape.cells[1]),
                                              static_cast<float>(g.shape.cells[2])) *
                                             (0.5f * g.shape.voxelSize);
    constexpr int W = 128;
    for (const Vec3 dir : {Vec3(0, 0.3f, 1), Vec3(0.2f, -0.9f, 0.4f), Vec3(-1, 0.1f, -0.3f)}) {
        SCOPED_TRACE(dir.x);
        CameraDesc d;
        d.target = centre;
        d.eye = centre + normalize(dir) * 0.45f;  // the bunny is about 0.16 across
        d.fovDeg = 30;
        d.width = d.height = W;
        const Camera camera(d);
        TraceOptions o;
        o.pixelRadius = camera.pixelRadius();
        std::vector<uint8_t> dda(W * W), local(W * W), old(W * W);
        for (int y = 0; y < W; ++y)
            for (int x = 0; x < W; ++x) {
                const Ray ray = camera.pixelRay(x, y);
                dda[y * W + x] = traceGridRay(g, ray, 0, 10, GridTraceOptions{}).hit;
                const TraceResult r = sphereTraceGrid(g, ray, o);
                local[y * W + x] = r.hit;
                old[y * W + x] = sphereTraceGrid(global, ray, o).hit;
                // The tape's grid primitive is this value.
                const TraceResult viaTape = traceRay(tape, {ray, 0, 10}, o);
                ASSERT_EQ(viaTape.hit, r.hit);
                ASSERT_EQ(viaTape.t, r.t);
            }
        int interior = 0, hits = 0, mismatch = 0, mismatchGlobal = 0;
        for (int y = 1; y + 1 < W; ++y)
            for (int x = 1; x + 1 < W; ++x) {
                bool edge = false;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx)
                        edge |= dda[(y + dy) * W + x + dx] != dda[y * W + x];
                if (edge) continue;
                ++interior;
                hits += dda[y * W + x];
                mismatch += dda[y * W + x] != local[y * W + x];
                mismatchGlobal += dda[y * W + x] != old[y * W + x];
            }
        std::printf(
            "view (%.1f, %.1f, %.1f): %d interior pixels, %d DDA hits; differing: %d "
            "with local bounds, %d with the global one\n",
            dir.x, dir.y, dir.z, interior, hits, mismatch, mismatchGlobal);
        EXPECT_GT(hits, interior / 10);
        EXPECT_LE(mismatch, hits / 10);
        EXPECT_LE(4 * mismatch, mismatchGlobal);
    }
}

}  // namespace
}  // namespace sdft
