// The two-level DDA grid tracer (Jamriška §4) against sphere tracing of the same trilinear field,
// and its accelerations (bit masks §4.1, occluder shadow rays §7) against the plain traversal.
#include "sdftrace/trace/grid_tracer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>

#include "sdftrace/exec/simd.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/test_util.h"
#include "sdftrace/trace/field_tracer.h"
#include "sdftrace/trace/minmax_buffer.h"

namespace sdft {
namespace {

struct Fixture {
    NodePtr analytic;
    std::shared_ptr<Grid> sparse, dense;
    std::vector<RaySegment> rays;
};

const Fixture& fixture() {
    static Fixture f = [] {
        Fixture x;
        x.analytic = node::unite({node::torus(0.8f, 0.25f),
                                  node::translate(node::box({0.5f, 0.6f, 0.5f}), {0, 0.2f, 0}),
                                  node::translate(node::sphere(0.35f), {-1.1f, 0.6f, 0.3f})});
        Tape tape = compileTape(x.analytic, {.boundsCulling = false});
        SampleOptions o;
        o.resolution = 80;
        GridShape shape = gridShapeFor(nodeBounds(*x.analytic), o);
        std::vector<float> samples = sampleVertices(tape, shape);
        x.sparse = std::make_shared<Grid>(Grid::sparseFromDense(shape, samples, 4, 3));
        x.dense = std::make_shared<Grid>(Grid::dense(shape, samples));
        testing::Rng rng(7);
        for (int i = 0; i < 3000; ++i) {
            Vec3 o3 = rng.direction() * 4.0f;
            x.rays.push_back({{o3, normalize(rng.inCube(1.3f) - o3)}, 0, 20});
        }
        return x;
    }();
    return f;
}

TEST(GridTracer, FindsTheFirstZeroOfTheReconstructionLikeSphereTracing) {
    const Fixture& f = fixture();
    GridView g = f.sparse->view();
    Tape gridTape = compileTape(node::grid(f.sparse));
    TraceOptions st = TraceOptions::classic();
    st.tau = 1e-5f;
    st.maxSteps = 5000;
    GridTraceOptions o;
    o.falsiIters = 4;
    int hits = 0, mismatch = 0;
    const float h = g.shape.voxelSize;
    for (const RaySegment& seg : f.rays) {
        GridTraceResult d = traceGridRay(g, seg.ray, seg.tMin, seg.tMax, o);
        TraceResult s = traceRay(gridTape, seg, st);
        if (d.hit != s.hit) {
            ++mismatch;  // a ray that enters and leaves the surface inside one cell (grazing)
            continue;
        }
        if (!d.hit) continue;
        ++hits;
        EXPECT_NEAR(d.t, s.t, 0.02f * h);
        EXPECT_LT(std::fabs(g.interpolate(seg.ray.at(d.t))), 0.01f * h);
    }
    EXPECT_GT(hits, 1000);
    EXPECT_LE(mismatch, static_cast<int>(f.rays.size()) / 200);
}

TEST(GridTracer, BitMasksAndDenseTraversalChangeNoHit) {
    const Fixture& f = fixture();
    GridTraceOptions masks, corners;
    corners.bitMasks = false;
    for (const RaySegment& seg : f.rays) {
        GridTraceResult a = traceGridRay(f.sparse->view(), seg.ray, seg.tMin, seg.tMax, masks);
        GridTraceResult b = traceGridRay(f.sparse->view(), seg.ray, seg.tMin, seg.tMax, corners);
        GridTraceResult c = traceGridRay(f.dense->view(), seg.ray, seg.tMin, seg.tMax, masks);
        ASSERT_EQ(a.hit, b.hit);
        ASSERT_EQ(a.t, b.t);
        ASSERT_EQ(a.traversalSteps, b.traversalSteps);
        ASSERT_EQ(a.hit, c.hit);
        if (a.hit) {
            ASSERT_NEAR(a.t, c.t, 1e-4f);
        }
    }
}

// Skipping cubes of blocks without a surface (GridView::blockSkip) changes no hit and no t, and
// saves traversal steps.
TEST(GridTracer, EmptySpaceSkippingChangesNoHit) {
    const Fixture& f = fixture();
    const GridView with = f.sparse->view();
    const GridView without = testing::withoutSkipping(with);
    ASSERT_NE(with.blockSkip, nullptr);
    ASSERT_NE(with.tileSkip, nullptr);
    int maxSkip = 0;
    for (uint8_t r : f.sparse->blockSkip()) maxSkip = std::max<int>(maxSkip, r);
    EXPECT_GE(maxSkip, 3);
    long stepsWith = 0, stepsWithout = 0;
    int hits = 0;
    for (const RaySegment& seg : f.rays) {
        GridTraceResult a = traceGridRay(with, seg.ray, seg.tMin, seg.tMax, GridTraceOptions{});
        GridTraceResult b = traceGridRay(without, seg.ray, seg.tMin, seg.tMax, GridTraceOptions{});
        ASSERT_EQ(a.hit, b.hit);
        if (a.hit) {
            ASSERT_EQ(a.t, b.t);
        }
        ASSERT_LE(a.traversalSteps, b.traversalSteps);
        ASSERT_EQ(a.intersectionTests, b.intersectionTests);
        hits += a.hit;
        stepsWith += a.traversalSteps;
        stepsWithout += b.traversalSteps;
    }
    EXPECT_GT(hits, 1000);
    EXPECT_LT(stepsWith, stepsWithout);
}

// A grid much larger than its surface: 1600^3 cells (50 tiles of 8^3 blocks per axis) holding two
// spheres of radius 12 cells at opposite corners, built straight into the two-level table (most
// tiles on the constant outside page).
Grid twoSpheresInALargeGrid() {
    GridShape shape;
    for (int a = 0; a < 3; ++a) shape.cells[a] = 1600;
    shape.voxelSize = 1;
    const int B = 4, V = B + 1;
    const float band = 3;
    const Vec3 centres[2] = {Vec3(150, 170, 160), Vec3(1450, 1420, 1440)};
    const int n[3] = {400, 400, 400};
    auto dist = [&](Vec3 p) {
        return std::min(length(p - centres[0]), length(p - centres[1])) - 12.0f;
    };
    BlockTable t = BlockTable::empty(n);
    std::map<size_t, uint8_t> flags;  // flat block -> flag, for blocks near a sphere
    for (const Vec3& c : centres)
        for (int bk = int(c.z) / B - 5; bk <= int(c.z) / B + 5; ++bk)
            for (int bj = int(c.y) / B - 5; bj <= int(c.y) / B + 5; ++bj)
                for (int bi = int(c.x) / B - 5; bi <= int(c.x) / B + 5; ++bi) {
                    bool neg = false, pos = false, near = false;
                    for (int k = 0; k < V; ++k)
                        for (int j = 0; j < V; ++j)
                            for (int i = 0; i < V; ++i) {
                                const float d = dist(Vec3(bi * B + i, bj * B + j, bk * B + k));
                                (d < 0 ? neg : pos) = true;
                                near |= std::fabs(d) < band;
                            }
                    flags[(static_cast<size_t>(bk) * 400 + bj) * 400 + bi] = near || (neg && pos)
                                                                                 ? 2
                                                                             : neg ? 1
                                                                                   : 0;
                }
    // Own pages in tile order.
    std::map<size_t, int32_t> pageOf;
    for (const auto& [b, f] : flags) {
        const int bi = b % 400, bj = b / 400 % 400, bk = b / 160000;
        pageOf[t.tileOf(bi, bj, bk)] = 0;
    }
    int32_t next = kFirstOwnPage;
    for (auto& [tile, page] : pageOf) t.tilePage[tile] = page = next++;
    t.flags.resize(static_cast<size_t>(next) * kPageEntries, 0);
    std::vector<float> samples;
    for (const auto& [b, f] : flags) {
        const int bi = b % 400, bj = b / 400 % 400, bk = b / 160000;
        t.flags[t.slot(bi, bj, bk)] = f;
        if (f != 2) continue;
        for (int k = 0; k < V; ++k)
            for (int j = 0; j < V; ++j)
                for (int i = 0; i < V; ++i)
                    samples.push_back(
                        std::clamp(dist(Vec3(bi * B + i, bj * B + j, bk * B + k)), -band, band));
    }
    return Grid::sparseFromTable(shape, B, band - 1, std::move(t), std::move(samples), "test");
}

TEST(GridTracer, TileSkippingAcrossALargeEmptyGridChangesNoHit) {
    const Grid g = twoSpheresInALargeGrid();
    const GridView with = g.view();
    const GridView without = testing::withoutSkipping(with);
    size_t own = 0;
    for (int32_t p : g.tilePage()) own += p >= kFirstOwnPage;
    EXPECT_LT(own, 30u);
    EXPECT_EQ(g.tilePage().size(), 50u * 50 * 50);
    testing::Rng rng(11);
    int hits = 0;
    long stepsWith = 0, stepsWithout = 0;
    const Vec3 centres[2] = {Vec3(150, 170, 160), Vec3(1450, 1420, 1440)};
    for (int n = 0; n < 400; ++n) {
        // From near one sphere towards the other, and from outside the grid at either.
        const Vec3 target = centres[n % 2] + rng.inCube(14.0f);
        const Vec3 from = n % 4 < 2 ? centres[1 - n % 2] + rng.inCube(30.0f)
                                    : Vec3(800.0f) + rng.direction() * 1500.0f;
        const Ray ray{from, normalize(target - from)};
        GridTraceResult a = traceGridRay(with, ray, 0, 1e5f, GridTraceOptions{});
        GridTraceResult b = traceGridRay(without, ray, 0, 1e5f, GridTraceOptions{});
        ASSERT_EQ(a.hit, b.hit) << n;
        if (a.hit) {
            ASSERT_EQ(a.t, b.t) << n;
        }
        ASSERT_EQ(a.intersectionTests, b.intersectionTests) << n;
        hits += a.hit;
        stepsWith += a.traversalSteps;
        stepsWithout += b.traversalSteps;
    }
    EXPECT_GT(hits, 150);
    // The plain DDA walks ~400 blocks per ray; skipping walks a few per tile it leaves.
    EXPECT_LT(stepsWith * 5, stepsWithout);
}

// Every walk ends: skipping a cube of tiles or blocks restarts the DDA where the ray leaves the
// cube, and rounding can put that point back inside the cube (a render of the rock's level set
// from a grazing camera once looped there forever). Rays from everywhere in the large grid, in
// every direction (axis-aligned and diagonal ones too), walk a bounded number of steps and agree
// with the plain traversal.
TEST(GridTracer, SkippingAlwaysMakesProgress) {
    const Grid g = twoSpheresInALargeGrid();
    const GridView with = g.view();
    const GridView without = testing::withoutSkipping(with);
    testing::Rng rng(5);
    for (int n = 0; n < 100000; ++n) {
        Vec3 from = rng.inBox(Vec3(-100.0f), Vec3(1700.0f));
        Vec3 dir = rng.direction();
        if (n % 5 == 0) dir[n % 3] = 0;  // rays in a grid plane
        if (n % 2 == 1) {
            // Through an edge where a tile face (x a multiple of 32 cells) meets a block face (y a
            // multiple of 4): the two crossings coincide, and round apart.
            const Vec3 edge(32.0f * static_cast<int>(rng.uniform(1, 49)),
                            4.0f * static_cast<int>(rng.uniform(1, 399)), rng.uniform(0, 1600));
            from = edge - dir * rng.uniform(20, 800);
        }
        const Ray ray{from, normalize(dir)};
        GridTraceResult a = traceGridRay(with, ray, 0, 1e5f, GridTraceOptions{});
        // A walk crosses at most 400 blocks per axis.
        ASSERT_LE(a.traversalSteps, 3 * 400 + 400) << n;
        if (n % 10 == 0) {
            GridTraceResult b = traceGridRay(without, ray, 0, 1e5f, GridTraceOptions{});
            ASSERT_EQ(a.hit, b.hit) << n;
            if (a.hit) {
                ASSERT_EQ(a.t, b.t) << n;
            }
        }
    }
}

// The skip distances are the Chebyshev distance to the nearest block with a sign-changing cell
// (exact up to 8, 9 beyond, on the blocks of own pages), and the tiles' to the nearest tile with
// one; the narrow band has surface blocks without one (which the DDA skips).
TEST(GridTracer, BlockSkipIsTheDistanceToTheNearestCrossingBlock) {
    const Grid& g = *fixture().sparse;
    const GridView v = g.view();
    const int nx = v.blocks[0], ny = v.blocks[1], nz = v.blocks[2];
    // Blocks with a cell whose corners change sign, found from the samples (not the masks).
    std::vector<std::array<int, 3>> crossing;
    size_t surfaceBlocks = 0;
    for (int k = 0; k < nz; ++k)
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                if (v.flags[v.blockSlot(i, j, k)] != 2) continue;
                ++surfaceBlocks;
                bool any = false;
                for (int z = k * v.blockSize; z < std::min((k + 1) * v.blockSize, v.shape.cells[2]);
                     ++z)
                    for (int y = j * v.blockSize;
                         y < std::min((j + 1) * v.blockSize, v.shape.cells[1]); ++y)
                        for (int x = i * v.blockSize;
                             x < std::min((i + 1) * v.blockSize, v.shape.cells[0]); ++x) {
                            float c[8];
                            v.cellCorners(x, y, z, c);
                            any |= cornersChangeSign(c);
                        }
                if (any) crossing.push_back({i, j, k});
            }
    ASSERT_FALSE(crossing.empty());
    EXPECT_LT(crossing.size(), surfaceBlocks);
    int checked = 0;
    for (size_t b = 0; b < static_cast<size_t>(nx) * ny * nz; b += 7) {
        const int i = static_cast<int>(b % nx), j = static_cast<int>(b / nx % ny),
                  k = static_cast<int>(b / (static_cast<size_t>(nx) * ny));
        if (v.tilePage[v.tileIndex(i, j, k)] < kFirstOwnPage) continue;
        int d = 1 << 30;
        for (const auto& s : crossing)
            d = std::min(d, std::max({std::abs(s[0] - i), std::abs(s[1] - j), std::abs(s[2] - k)}));
        ASSERT_EQ(v.blockSkip[v.blockSlot(i, j, k)], std::min(kTileBlocks + 1, d))
            << i << " " << j << " " << k;
        ++checked;
    }
    EXPECT_GT(checked, 100);
    // Tiles: the same distance on the tile grid.
    for (int k = 0; k < v.tiles[2]; ++k)
        for (int j = 0; j < v.tiles[1]; ++j)
            for (int i = 0; i < v.tiles[0]; ++i) {
                int d = 1 << 30;
                for (const auto& s : crossing)
                    d = std::min(d, std::max({std::abs(s[0] / kTileBlocks - i),
                                              std::abs(s[1] / kTileBlocks - j),
                                              std::abs(s[2] / kTileBlocks - k)}));
                ASSERT_EQ(v.tileSkip[(static_cast<size_t>(k) * v.tiles[1] + j) * v.tiles[0] + i],
                          std::min(255, d))
                    << "tile " << i << " " << j << " " << k;
            }
}

// The AVX2 and baseline builds of the tracer (exec/simd.h) take the same steps and return the
// same hits, parameters, shadow decisions and normals.
TEST(GridTracer, BothSimdLevelsTraceAlike) {
    if (!cpuHasAvx2()) GTEST_SKIP() << "this CPU has no AVX2: only the baseline build runs";
    const Fixture& f = fixture();
    const GridView v = f.sparse->view();
    const SimdLevel was = simdLevel();
    int hits = 0;
    for (const RaySegment& seg : f.rays) {
        GridTraceResult r[2], sh[2];
        Vec3 n[2][3];
        for (int level = 0; level < 2; ++level) {
            setSimdLevel(level ? SimdLevel::Avx2 : SimdLevel::Baseline);
            r[level] = traceGridRay(v, seg.ray, seg.tMin, seg.tMax, GridTraceOptions{});
            sh[level] = traceGridShadow(v, seg.ray, seg.tMin, seg.tMax, GridTraceOptions{}, 3);
            const Vec3 p = seg.ray.at(r[level].hit ? r[level].t : seg.tMin);
            for (int m = 0; m < 3; ++m) n[level][m] = gridNormal(v, p, static_cast<GridNormal>(m));
        }
        ASSERT_EQ(r[0].hit, r[1].hit);
        ASSERT_EQ(r[0].t, r[1].t);
        ASSERT_EQ(r[0].traversalSteps, r[1].traversalSteps);
        ASSERT_EQ(sh[0].hit, sh[1].hit);
        ASSERT_EQ(sh[0].t, sh[1].t);
        for (int m = 0; m < 3; ++m) {
            ASSERT_EQ(n[0][m].x, n[1][m].x);
            ASSERT_EQ(n[0][m].y, n[1][m].y);
            ASSERT_EQ(n[0][m].z, n[1][m].z);
        }
        hits += r[0].hit;
    }
    setSimdLevel(was);
    EXPECT_GT(hits, 1000);
}

TEST(GridTracer, MidpointStaysWithinTheHitCell) {
    const Fixture& f = fixture();
    GridView g = f.sparse->view();
    GridTraceOptions fp, mid;
    mid.cellMethod = CellIntersection::Midpoint;
    int compared = 0;
    for (const RaySegment& seg : f.rays) {
        GridTraceResult a = traceGridRay(g, seg.ray, seg.tMin, seg.tMax, fp);
        GridTraceResult b = traceGridRay(g, seg.ray, seg.tMin, seg.tMax, mid);
        if (b.hit) {
            EXPECT_LE(b.intersectionTests, a.hit ? a.intersectionTests : 1 << 30);
        }
        if (!a.hit || !b.hit) continue;
        // The midpoint method stops in the first surface cell, at or before false position's cell.
        EXPECT_LE(b.t, a.t + 1.8f * g.shape.voxelSize);
        EXPECT_EQ(b.interpolations, 0);
        ++compared;
    }
    EXPECT_GT(compared, 1000);
}

TEST(GridTracer, OccluderShadowRaysChangeNoDecisionAndTestFewerCells) {
    const Fixture& f = fixture();
    GridView g = f.sparse->view();
    GridTraceOptions o;
    testing::Rng rng(8);
    long testsPlain = 0, testsOccluder = 0;
    int blocked = 0;
    for (int i = 0; i < 4000; ++i) {
        // Shadow rays from points around the objects towards random directions.
        Vec3 start = rng.inCube(1.6f);
        if (g.sample(start) <= 0.02f) continue;
        Ray r{start, rng.direction()};
        GridTraceResult plain = traceGridRay(g, r, 0, 20, o);
        for (int n : {12, 32}) {
            GridTraceResult occ = traceGridShadow(g, r, 0, 20, o, n);
            ASSERT_EQ(occ.hit, plain.hit) << "n=" << n;
            if (n == 12) testsOccluder += occ.intersectionTests;
        }
        testsPlain += plain.intersectionTests;
        blocked += plain.hit;
    }
    EXPECT_GT(blocked, 300);
    EXPECT_LT(testsOccluder, testsPlain);
}

// Jamriška §6: narrowing primary rays to their min/max-buffer interval changes no hit, from cameras
// far and near (a block reaching the camera plane disables the bound), at three resolutions.
TEST(GridTracer, MinMaxBuffersChangeNoHitAndSaveTraversalSteps) {
    const Fixture& f = fixture();
    GridView g = f.sparse->view();
    GridTraceOptions o;
    testing::Rng rng(10);
    long stepsPlain = 0, stepsBuffered = 0;
    int hits = 0;
    for (int c = 0; c < 6; ++c) {
        CameraDesc d;
        d.eye = rng.direction() * (c < 4 ? rng.uniform(2.5f, 6.0f) : rng.uniform(0.3f, 1.2f));
        d.target = rng.inCube(0.3f);
        d.fovDeg = rng.uniform(25.0f, 70.0f);
        d.width = 96;
        d.height = 64;
        Camera cam(d);
        for (int res : {64, 128, 256}) {
            MinMaxBuffer buf = MinMaxBuffer::build(g, cam, res);
            for (int y = 0; y < d.height; ++y)
                for (int x = 0; x < d.width; ++x) {
                    Ray r = cam.pixelRay(x, y);
                    GridTraceResult plain = traceGridRay(g, r, 0, 100, o);
                    float t0, t1;
                    buf.range(x, y, t0, t1);
                    GridTraceResult b = t0 <= t1 ? traceGridRay(g, r, t0, std::min(t1, 100.0f), o)
                                                 : GridTraceResult{};
                    ASSERT_EQ(plain.hit, b.hit)
                        << "camera " << c << " res " << res << " pixel " << x << "," << y;
                    if (plain.hit) {
                        ASSERT_NEAR(plain.t, b.t, 1e-4f * plain.t);
                    }
                    stepsPlain += plain.traversalSteps;
                    stepsBuffered += b.traversalSteps;
                    hits += plain.hit;
                }
        }
    }
    EXPECT_GT(hits, 5000);
    EXPECT_LT(stepsBuffered, stepsPlain);
}

// A 64 x 48 camera at `eye` looking at `target`.
CameraDesc cameraAt(Vec3 eye, Vec3 target, float fovDeg) {
    CameraDesc d;
    d.eye = eye;
    d.target = target;
    d.fovDeg = fovDeg;
    d.width = 64;
    d.height = 48;
    return d;
}

// A primary ray starts at the eye, or where the min/max buffer starts it after no surface block:
// the eye's sign (gridSignAt) is every primary ray's start sign, so passing it changes no result,
// from outside the grid's box, inside it and inside the solid.
TEST(GridTracer, TheEyesSignIsEveryPrimaryRaysStartSign) {
    const Fixture& f = fixture();
    const GridView g = f.sparse->view();
    const GridTraceOptions o;
    struct View {
        Vec3 eye, target;
        float sign;
    };
    const View views[] = {{{0.3f, 0.5f, 4.5f}, {0, 0.1f, 0}, 1},            // outside the box
                          {{0.2f, 1.1f, 0.9f}, {0, 0.2f, 0}, 1},            // in the box, outside
                          {{0.1f, 0.3f, -0.1f}, {-1.1f, 0.6f, 0.3f}, -1}};  // inside the box shape
    int hits = 0;
    for (const View& v : views) {
        EXPECT_EQ(gridSignAt(g, v.eye), v.sign);
        const CameraDesc d = cameraAt(v.eye, v.target, 60);
        const Camera cam(d);
        for (int res : {0, 128}) {
            const MinMaxBuffer buf = res ? MinMaxBuffer::build(g, cam, res) : MinMaxBuffer{};
            for (int y = 0; y < d.height; ++y)
                for (int x = 0; x < d.width; ++x) {
                    const Ray r = cam.pixelRay(x, y);
                    float t0, t1;
                    buf.range(x, y, t0, t1);
                    if (!(t0 <= t1)) continue;
                    const GridTraceResult looked = traceGridRay(g, r, t0, t1, o);
                    const GridTraceResult given = traceGridRay(g, r, t0, t1, o, v.sign);
                    ASSERT_EQ(looked.hit, given.hit)
                        << "eye " << v.eye.x << " pixel " << x << "," << y;
                    ASSERT_EQ(looked.t, given.t);
                    ASSERT_EQ(looked.traversalSteps, given.traversalSteps);
                    ASSERT_EQ(looked.intersectionTests, given.intersectionTests);
                    hits += looked.hit;
                }
        }
    }
    EXPECT_GT(hits, 4000);
}

// Blocks behind the camera or outside its view frustum are never met by a primary ray: they do not
// disable the bound (a block reaching the camera plane in view still does). Looking away from the
// surface every range is empty; looking past it from beside it, the pixels off the surface have
// empty ranges and the others a positive start, and no hit changes.
TEST(GridTracer, MinMaxBuffersIgnoreBlocksBehindTheCamera) {
    const Fixture& f = fixture();
    GridView g = f.sparse->view();
    GridTraceOptions o;
    struct View {
        Vec3 eye, target;
    };
    for (const View& v : {View{{0, 0.2f, 2.2f}, {0, 0.2f, 6}},            // looking away
                          View{{0.2f, 0.2f, 1.6f}, {-1.5f, 0.2f, 1.0f}},  // past the sphere
                          View{{2.0f, 0.1f, 0.0f}, {2.0f, 0.1f, -3.0f}}}) {
        const CameraDesc d = cameraAt(v.eye, v.target, 40);
        Camera cam(d);
        MinMaxBuffer buf = MinMaxBuffer::build(g, cam, 64);
        int empty = 0, bounded = 0, hits = 0;
        for (int y = 0; y < d.height; ++y)
            for (int x = 0; x < d.width; ++x) {
                float t0, t1;
                buf.range(x, y, t0, t1);
                empty += t0 > t1;
                bounded += t0 > 0 && t0 <= t1;
                Ray r = cam.pixelRay(x, y);
                GridTraceResult plain = traceGridRay(g, r, 0, 100, o);
                GridTraceResult b =
                    t0 <= t1 ? traceGridRay(g, r, t0, std::min(t1, 100.0f), o) : GridTraceResult{};
                ASSERT_EQ(plain.hit, b.hit) << "eye " << v.eye.x << " pixel " << x << "," << y;
                if (plain.hit) {
                    ASSERT_NEAR(plain.t, b.t, 1e-4f * plain.t);
                }
                hits += plain.hit;
            }
        const int pixels = d.width * d.height;
        if (hits == 0) {
            EXPECT_EQ(empty, pixels) << "eye " << v.eye.x;  // nothing in view
        } else {
            EXPECT_GT(empty, pixels / 10) << "eye " << v.eye.x;
            EXPECT_GT(bounded, hits / 2) << "eye " << v.eye.x;
        }
    }
}

// The gradient a hit carries is the analytic estimator's in the cell the hit was found in: where
// the hit point lies inside that cell (not on a face, where the neighbour's reconstruction may
// take over), gridNormal at the point gives the same normal; on every hit, gridHitNormal is its
// unit vector and faces against the ray where the ray entered from outside.
TEST(GridTracer, HitsCarryTheAnalyticGradientOfTheirCell) {
    const Fixture& f = fixture();
    for (const Grid* grid : {f.sparse.get(), f.dense.get()})
        for (CellIntersection method :
             {CellIntersection::FalsePosition, CellIntersection::Midpoint}) {
            const GridView g = grid->view();
            GridTraceOptions o;
            o.cellMethod = method;
            int hits = 0, interior = 0;
            for (const RaySegment& seg : f.rays) {
                const GridTraceResult r = traceGridRay(g, seg.ray, seg.tMin, seg.tMax, o);
                if (!r.hit) {
                    EXPECT_EQ(length(r.gradient), 0.0f);
                    continue;
                }
                ++hits;
                const Vec3 p = seg.ray.at(r.t);
                const Vec3 n = gridHitNormal(g, r, p, GridNormal::AnalyticTrilinear);
                EXPECT_NEAR(length(n), 1.0f, 1e-5f);
                if (method == CellIntersection::FalsePosition)
                    EXPECT_LT(dot(n, seg.ray.direction), 0.0f);  // the rays start outside
                const Vec3 q = (p - g.shape.origin) / g.shape.voxelSize;
                bool inside = true;
                for (int a = 0; a < 3; ++a) {
                    const float frac = q[a] - std::floor(q[a]);
                    inside &= frac > 1e-3f && frac < 1 - 1e-3f;
                }
                if (!inside) continue;
                ++interior;
                const Vec3 at = gridNormal(g, p, GridNormal::AnalyticTrilinear);
                EXPECT_GT(dot(at, n), 0.9999f) << "t " << r.t;
            }
            EXPECT_GT(hits, 1000);
            EXPECT_GT(interior, hits / 2);
        }
}

TEST(GridTracer, AllThreeGradientEstimatorsMatchTheSphereNormal) {
    Tape tape = compileTape(node::sphere(1.0f), {.boundsCulling = false});
    SampleOptions o;
    o.resolution = 48;
    Grid grid = sampleGrid(tape, {Vec3(-1.0f), Vec3(1.0f)}, o);
    GridView g = grid.view();
    testing::Rng rng(9);
    for (GridNormal m : {GridNormal::AnalyticTrilinear, GridNormal::DifferenceOfInterpolations,
                         GridNormal::InterpolationOfDifferences}) {
        for (int i = 0; i < 2000; ++i) {
            Vec3 u = rng.direction();
            EXPECT_GT(dot(gridNormal(g, u, m), u), 0.998f)
                << static_cast<int>(m);  // within 3.6 degrees
        }
    }
}

}  // namespace
}  // namespace sdft
