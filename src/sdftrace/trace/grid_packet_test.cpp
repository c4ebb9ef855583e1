// Packets of eight rays through the DDA (trace/grid_packet.cpp) against traceGridRay on each ray:
// the same hit, t and counters, bit for bit, on coherent camera rays (close, far, grazing, from
// inside the grid) and on incoherent ones, both block sizes, with and without empty-space
// skipping, and across tiles that are skipped whole.
#include <gtest/gtest.h>

#include <vector>

#include "sdftrace/exec/simd.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/test_util.h"
#include "sdftrace/trace/grid_tracer.h"

namespace sdft {
namespace {

struct Rays {
    std::vector<Ray> rays;
    std::vector<float> tMin, tMax;
    void add(const Ray& r, float lo, float hi) {
        rays.push_back(r);
        tMin.push_back(lo);
        tMax.push_back(hi);
    }
};

// A pinhole camera's rays, row by row (the order a tile hands them over).
void addCamera(Rays& out, Vec3 eye, Vec3 target, float fov, int w, int h) {
    const Vec3 forward = normalize(target - eye);
    const Vec3 right = normalize(cross(forward, Vec3(0, 1, 0.01f)));
    const Vec3 up = cross(right, forward);
    const float s = std::tan(0.5f * fov);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float u = (2 * (x + 0.5f) / w - 1) * s, v = (1 - 2 * (y + 0.5f) / h) * s;
            out.add({eye, normalize(forward + right * u + up * v)}, 0, 50);
        }
}

Grid gridOf(const NodePtr& root, int resolution, int blockSize) {
    SampleOptions o;
    o.resolution = resolution;
    o.blockSize = blockSize;
    return sampleGrid(compileTape(root, {.boundsCulling = false}), nodeBounds(*root), o);
}

// Every field of every result equal to traceGridRay's on the same ray; returns the hits.
int expectSameAsSingleRays(const GridView& g, const Rays& r, const GridTraceOptions& o,
                           float startSign = 0) {
    const int n = static_cast<int>(r.rays.size());
    std::vector<GridTraceResult> packet(n);
    traceGridRays(g, r.rays.data(), r.tMin.data(), r.tMax.data(), n, o, packet.data(), startSign);
    int hits = 0;
    for (int i = 0; i < n; ++i) {
        const GridTraceResult one =
            r.tMin[i] <= r.tMax[i] ? traceGridRay(g, r.rays[i], r.tMin[i], r.tMax[i], o, startSign)
                                   : GridTraceResult{};
        EXPECT_EQ(packet[i].hit, one.hit) << "ray " << i;
        EXPECT_EQ(packet[i].t, one.t) << "ray " << i;
        EXPECT_EQ(packet[i].traversalSteps, one.traversalSteps) << "ray " << i;
        EXPECT_EQ(packet[i].intersectionTests, one.intersectionTests) << "ray " << i;
        EXPECT_EQ(packet[i].interpolations, one.interpolations) << "ray " << i;
        for (int a = 0; a < 3; ++a)
            EXPECT_EQ(packet[i].gradient[a], one.gradient[a]) << "ray " << i;
        if (packet[i].hit != one.hit || packet[i].t != one.t) return hits;
        hits += one.hit;
    }
    return hits;
}

NodePtr shapes() {
    return node::unite({node::torus(0.8f, 0.25f),
                        node::translate(node::box({0.5f, 0.6f, 0.5f}), {0, 0.2f, 0}),
                        node::translate(node::sphere(0.35f), {-1.1f, 0.6f, 0.3f})});
}

Rays varietyOfRays() {
    Rays r;
    addCamera(r, {0.3f, 0.5f, 4.5f}, {0, 0.1f, 0}, 0.8f, 48, 32);     // framed
    addCamera(r, {0.2f, 0.4f, 1.2f}, {0, 0.2f, 0}, 1.2f, 48, 32);     // close: fills the view
    addCamera(r, {3.5f, 0.52f, 0.4f}, {0, 0.45f, 0}, 0.6f, 48, 32);   // grazing the box's top
    addCamera(r, {0.0f, 0.3f, 0.0f}, {1, 0.2f, 0.3f}, 1.4f, 40, 24);  // from inside the grid
    testing::Rng rng(11);
    for (int i = 0; i < 1500; ++i) {  // incoherent: a lane per direction
        const Vec3 o = rng.direction() * rng.uniform(0.5f, 4);
        r.add({o, normalize(rng.inCube(1.3f) - o)}, 0, 20);
    }
    // Axis-aligned directions (zero components: infinite boundaries), tMin past tMax, a short
    // segment, a ray that misses the grid.
    const Vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int i = 0; i < 60; ++i) r.add({rng.inCube(1.2f) - axes[i % 6] * 3, axes[i % 6]}, 0, 20);
    // A whole packet that a min/max buffer empties (rays 7,128 to 7,135).
    for (int i = 0; i < 8; ++i) r.add({{0, 0.2f, 3}, -axes[i % 6]}, 2, 1);
    r.add({{0, 0.2f, 3}, {0, 0, -1}}, 5, 1);
    r.add({{0, 0.2f, 3}, {0, 0, -1}}, 0.5f, 2.6f);
    r.add({{9, 9, 9}, {0, 1, 0}}, 0, 20);
    return r;  // 7,139 rays: the last packet has 3 lanes
}

TEST(GridPacket, EveryLaneEqualsTheSingleRayTraversal) {
    if (!cpuHasAvx2()) GTEST_SKIP() << "no AVX2: traceGridRays traces ray by ray";
    const Rays rays = varietyOfRays();
    for (int B : {4, 8}) {
        const Grid grid = gridOf(shapes(), 96, B);
        for (bool skipping : {true, false}) {
            const GridView v = skipping ? grid.view() : testing::withoutSkipping(grid.view());
            SCOPED_TRACE(::testing::Message() << "B " << B << ", skipping " << skipping);
            EXPECT_GT(expectSameAsSingleRays(v, rays, GridTraceOptions{}), 2000);
        }
    }
}

TEST(GridPacket, EqualWithEveryCellMethod) {
    if (!cpuHasAvx2()) GTEST_SKIP() << "no AVX2: traceGridRays traces ray by ray";
    const Rays rays = varietyOfRays();
    const Grid grid = gridOf(shapes(), 64, 4);
    GridTraceOptions o;
    o.falsiIters = 4;
    EXPECT_GT(expectSameAsSingleRays(grid.view(), rays, o), 2000);
    o.cellMethod = CellIntersection::Midpoint;
    EXPECT_GT(expectSameAsSingleRays(grid.view(), rays, o), 2000);
    o = {};
    o.bitMasks = false;  // the corners' signs: ray by ray
    EXPECT_GT(expectSameAsSingleRays(grid.view(), rays, o), 2000);
}

// Two small spheres at opposite corners of a grid 256 cells across: most tiles between them are
// skipped whole (tileSkip), and rays cross blocks of every kind.
TEST(GridPacket, EqualAcrossSkippedTiles) {
    if (!cpuHasAvx2()) GTEST_SKIP() << "no AVX2: traceGridRays traces ray by ray";
    const NodePtr root = node::unite({node::translate(node::sphere(0.3f), {-4, -4, -4}),
                                      node::translate(node::sphere(0.25f), {4, 4, 3.5f})});
    for (int B : {4, 8}) {
        const Grid grid = gridOf(root, 256, B);
        ASSERT_FALSE(grid.tileSkip().empty());
        Rays rays;
        addCamera(rays, {-4, -4, 2}, {-4, -4, -4}, 0.4f, 48, 32);   // at one sphere
        addCamera(rays, {-6, -5, -6}, {4, 4, 3.5f}, 0.1f, 48, 32);  // across the grid at the other
        testing::Rng rng(5);
        for (int i = 0; i < 1000; ++i) {
            const Vec3 o = rng.inCube(4.5f), target = i % 2 ? Vec3(-4) : Vec3(4, 4, 3.5f);
            rays.add({o, normalize(target + rng.inCube(0.4f) - o)}, 0, 40);
        }
        SCOPED_TRACE(::testing::Message() << "B " << B);
        EXPECT_GT(expectSameAsSingleRays(grid.view(), rays, GridTraceOptions{}), 500);
    }
}

// A camera's rays with the eye's sign given (traceGridRays' startSign), from outside the solid
// and from inside it.
TEST(GridPacket, EqualWithTheStartSignGiven) {
    if (!cpuHasAvx2()) GTEST_SKIP() << "no AVX2: traceGridRays traces ray by ray";
    const Grid grid = gridOf(shapes(), 64, 4);
    const GridView g = grid.view();
    for (Vec3 eye : {Vec3(0.2f, 0.4f, 1.2f), Vec3(0.1f, 0.3f, -0.1f)}) {
        Rays rays;
        addCamera(rays, eye, {-1.1f, 0.6f, 0.3f}, 1.2f, 48, 32);
        const float sign = gridSignAt(g, eye);
        SCOPED_TRACE(::testing::Message() << "sign " << sign);
        EXPECT_GT(expectSameAsSingleRays(g, rays, GridTraceOptions{}, sign), 500);
    }
}

TEST(GridPacket, TheBaselineTracesRayByRayAlike) {
    const Rays rays = varietyOfRays();
    const Grid grid = gridOf(shapes(), 64, 4);
    const SimdLevel was = simdLevel();
    setSimdLevel(SimdLevel::Baseline);
    EXPECT_GT(expectSameAsSingleRays(grid.view(), rays, GridTraceOptions{}), 2000);
    setSimdLevel(was);
}

}  // namespace
}  // namespace sdft
