// Every bake method against meshes whose SDF is known in closed form (box, sphere, torus), with
// the bound each one is held to; signs by each sign method; and the bunny baked and rendered
// through the grid tracer against Embree's ray casting of the same triangles.
#include "sdftrace/bake/mesh_bake.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "sdftrace/bake/exact_bake.h"
#include "sdftrace/bake/test_meshes.h"
#include "sdftrace/bake/verify_bake.h"
#include "sdftrace/bake/winding_number.h"
#include "sdftrace/core/error.h"
#include "sdftrace/field/primitives.h"
#include "sdftrace/io/mesh_io.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/grid_scene.h"
#include "sdftrace/scene/plan_render.h"

namespace sdft {
namespace {

struct ClosedForm {
    const char* name;
    TriangleMesh mesh;
    float gap;  // how far the triangles stray from the smooth surface
    float (*sdf)(Vec3);
};

std::vector<ClosedForm> closedFormMeshes() {
    std::vector<ClosedForm> out;
    out.push_back({"box", testing::boxMesh(Vec3(0.5f, 0.3f, 0.7f)), 0.0f, [](Vec3 p) {
                       const float h[3] = {0.5f, 0.3f, 0.7f};
                       return prim::box(p, h);
                   }});
    TriangleMesh sphere = testing::icosphere(4);
    float gap = 0;
    for (auto [a, b, c] : sphere.triangles)
        gap = std::max(
            gap,
            1 - length((sphere.positions[a] + sphere.positions[b] + sphere.positions[c]) / 3.0f));
    out.push_back({"sphere", sphere, gap, [](Vec3 p) { return length(p) - 1; }});
    out.push_back({"torus", testing::torusMesh(1, 0.35f, 160, 64),
                   testing::torusTessellationGap(1, 0.35f, 160, 64), [](Vec3 p) {
                       float q = std::sqrt(p.x * p.x + p.y * p.y) - 1;
                       return std::sqrt(q * q + p.z * p.z) - 0.35f;
                   }});
    return out;
}

// The bound each method is held to, in voxels beyond the tessellation gap, at 48 cells (dense).
// Measured (box / sphere / torus): jfa band mean 0 / 0.033 / 0.027, max 0 / 0.18 / 0.16;
// danielsson 0 / 0.040 / 0.033, all-sample max 0.45; edt 0 / 0.042 / 0.035, max 0.38; rtsdf
// (x = 64, d = 3) band mean 0.065 / 0.057 / 0.055, p99 0.57 / 0.33 / 0.33.
struct Bound {
    MeshBakeMethod method;
    double bandMean, bandMax, allMax;  // allMax < 0: not bounded (see rtsdf below)
};

TEST(MeshBake, EveryMethodWithinItsBoundOfClosedFormSdfs) {
    const Bound bounds[] = {
        {MeshBakeMethod::Exact, 1e-4, 1e-4, 1e-4},
        {MeshBakeMethod::JumpFlood, 0.05, 0.3, 0.4},
        {MeshBakeMethod::Danielsson, 0.06, 0.3, 0.7},
        {MeshBakeMethod::SeparableEdt, 0.06, 0.3, 0.6},
    };
    for (const ClosedForm& m : closedFormMeshes()) {
        for (const Bound& b : bounds) {
            MeshBakeOptions o;
            o.method = b.method;
            o.sampling.resolution = 48;
            o.sampling.kind = GridKind::Dense;
            Grid g = bakeMesh(m.mesh, o).grid;
            const GridShape& s = g.shape();
            GridView v = g.view();
            const float h = s.voxelSize, gap = m.gap / h;
            double sum = 0, worst = 0, worstBand = 0;
            size_t n = 0, wrong = 0;
            for (int k = 0; k <= s.cells[2]; ++k)
                for (int j = 0; j <= s.cells[1]; ++j)
                    for (int i = 0; i <= s.cells[0]; ++i) {
                        float exact = m.sdf(s.origin + Vec3(i, j, k) * h);
                        float baked = v.vertex(i, j, k);
                        if (std::fabs(exact) > m.gap * 1.01f) wrong += (baked < 0) != (exact < 0);
                        double e = std::max(0.0, double(std::fabs(baked - exact) / h - gap));
                        worst = std::max(worst, e);
                        if (std::fabs(exact) < 3 * h) {
                            sum += e;
                            ++n;
                            worstBand = std::max(worstBand, e);
                        }
                    }
            const char* name = meshBakeMethodName(b.method);
            EXPECT_EQ(wrong, 0u) << m.name << " " << name;
            EXPECT_LT(sum / n, b.bandMean) << m.name << " " << name;
            EXPECT_LT(worstBand, b.bandMax) << m.name << " " << name;
            EXPECT_LT(worst, b.allMax) << m.name << " " << name;
        }
    }
}

// RTSDF's ray sampling: the minimum over x random directions. Near the surface it is within a
// stated bound on average. Where the closest point is a convex edge or corner seen through a small
// solid angle the rays may all miss it (10 voxels off next to the box's corners at x = 64 once):
// the relaxation to 1-Lipschitz along the axes, and the coarse distance standing in where no hit
// is near, keep the maximum within 2 voxels.
TEST(MeshBake, RtsdfWithinItsBoundAndNeverBelowTheDistance) {
    for (const ClosedForm& m : closedFormMeshes()) {
        MeshBakeOptions o;
        o.method = MeshBakeMethod::Rtsdf;
        o.rtsdf.rays = 64;
        o.rtsdf.maskVoxels = 3;
        o.sampling.resolution = 48;
        o.sampling.kind = GridKind::Dense;
        Grid g = bakeMesh(m.mesh, o).grid;
        const GridShape& s = g.shape();
        MeshBvh bvh(m.mesh);
        std::vector<float> exact = bakeExactSamples(bvh, s, SignMethod::WindingNumber);
        BakeVerification ver = verifyBake(g, exact, 3);
        EXPECT_EQ(ver.wrongSigns, 0u) << m.name;
        EXPECT_LT(ver.band.mean, 0.2) << m.name;
        EXPECT_LT(ver.band.p99, 1.5) << m.name;
        EXPECT_LT(ver.band.max, 2.0) << m.name;
        // Ray hits lie on the mesh: never closer than its closest point.
        GridView v = g.view();
        size_t n = 0;
        for (int k = 0; k <= s.cells[2]; ++k)
            for (int j = 0; j <= s.cells[1]; ++j)
                for (int i = 0; i <= s.cells[0]; ++i, ++n)
                    if (std::fabs(exact[n]) < 2 * s.voxelSize) {
                        ASSERT_GE(std::fabs(v.vertex(i, j, k)), std::fabs(exact[n]) - 1e-5f)
                            << m.name;
                    }
        // More rays, closer: the mean band error falls.
        o.rtsdf.rays = 256;
        BakeVerification more = verifyBake(bakeMesh(m.mesh, o).grid, exact, 3);
        EXPECT_LT(more.band.mean, ver.band.mean) << m.name;
    }
}

// The propagation methods measure to points on the surface, so they never undercut the exact
// distance; on real meshes (closed bunny, open elephant) they stay within their bounds of it.
TEST(MeshBake, PropagationMethodsBoundTheExactDistanceFromAbove) {
    for (const char* file : {"bunny_npm.obj", "elephant-with-holes.obj"}) {
        TriangleMesh mesh = loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + file);
        for (MeshBakeMethod method : {MeshBakeMethod::JumpFlood, MeshBakeMethod::Danielsson,
                                      MeshBakeMethod::SeparableEdt}) {
            MeshBakeOptions o;
            o.method = method;
            o.sampling.resolution = 40;
            o.sampling.kind = GridKind::Dense;
            Grid g = bakeMesh(mesh, o).grid;
            MeshBvh bvh(mesh);
            std::vector<float> exact = bakeExactSamples(bvh, g.shape(), SignMethod::WindingNumber);
            for (size_t i = 0; i < exact.size(); ++i)
                ASSERT_GE(std::fabs(g.samples()[i]), std::fabs(exact[i]) - 1e-5f) << file;
            BakeVerification v = verifyBake(g, exact, 3);
            EXPECT_EQ(v.wrongSigns, 0u) << file << " " << meshBakeMethodName(method);
            EXPECT_LT(v.band.mean, 0.08) << file << " " << meshBakeMethodName(method);
            EXPECT_LT(v.all.max, 1.6) << file << " " << meshBakeMethodName(method);
        }
    }
}

TEST(MeshBake, JumpFloodVariantsRunTheirPasses) {
    TriangleMesh sphere = testing::icosphere(3);
    for (auto [variant, extra] : {std::pair{JfaVariant::Plain, 0},
                                  {JfaVariant::OnePlusJfa, 1},
                                  {JfaVariant::JfaPlusTwo, 2}}) {
        SampleOptions so;
        so.resolution = 40;  // 45 vertices along the longest axis: offsets 32 ... 1
        GridShape shape = gridShapeFor(sphere.bounds(), so);
        JfaStats st;
        jumpFlood(shape, seedSurfaceVertices(sphere, shape).point, variant, 0, &st);
        EXPECT_EQ(st.offsets.size(), 6u + extra);
        EXPECT_EQ(st.offsets.front(), variant == JfaVariant::OnePlusJfa ? 1 : 32);
        EXPECT_EQ(st.passSeconds.size(), st.offsets.size());
    }
}

// Flood fill (from the grid's boundary, through vertices clear of the voxelized surface) agrees
// with the winding number on closed meshes; the beta shell is |d| - beta, hollow inside.
TEST(MeshBake, FloodFillAndBetaShellSigns) {
    TriangleMesh mesh = loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/bunny_npm.obj");
    MeshBakeOptions o;
    o.method = MeshBakeMethod::JumpFlood;
    o.sampling.resolution = 40;
    o.sampling.kind = GridKind::Dense;
    std::vector<float> winding = bakeMesh(mesh, o).grid.samples();
    o.sign = SignMethod::FloodFill;
    std::vector<float> flood = bakeMesh(mesh, o).grid.samples();
    o.sign = SignMethod::BetaShell;
    o.betaVoxels = 0.5f;
    Grid beta = bakeMesh(mesh, o).grid;
    float h = beta.shape().voxelSize;
    size_t inside = 0, shell = 0;
    for (size_t i = 0; i < winding.size(); ++i) {
        ASSERT_EQ(flood[i], winding[i]);
        ASSERT_FLOAT_EQ(beta.samples()[i], std::fabs(winding[i]) - 0.5f * h);
        inside += winding[i] < 0;
        shell += beta.samples()[i] < 0;
    }
    EXPECT_GT(inside, 2000u);
    EXPECT_LT(shell, inside);  // the paper's shell: deep inside stays positive
    // Exact and rtsdf have no voxelized surface to flood.
    o.method = MeshBakeMethod::Exact;
    o.sign = SignMethod::FloodFill;
    EXPECT_THROW(bakeMesh(mesh, o), InputError);
}

// Sparse output: the band bake gives the same grid as sparsifying the dense exact bake, and
// blocks far inside are flagged inside.
TEST(MeshBake, SparseExactBandBakeEqualsTheSparsifiedDenseBake) {
    for (const char* file : {"bunny_npm.obj", "teapot.obj"}) {
        TriangleMesh mesh = loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + file);
        MeshBvh bvh(mesh);
        for (int block : {4, 8}) {
            SampleOptions so;
            so.resolution = 44;
            GridShape shape = gridShapeFor(mesh.bounds(), so);
            ExactBakeStats st;
            Grid band = bakeExactSparse(mesh, shape, block, 3, SignMethod::WindingNumber, 0, &st);
            // Bit for bit against the BVH's distances (both in world units); within rounding
            // against the closest point transform's (in voxel units).
            Grid dense =
                Grid::sparseFromDense(shape,
                                      bakeExactSamples(bvh, shape, SignMethod::WindingNumber, 0,
                                                       nullptr, false, ClosestPoints::Bvh),
                                      block, 3);
            EXPECT_EQ(band.flags(), dense.flags()) << file << " B=" << block;
            EXPECT_EQ(band.expandedBlockSamples(), dense.expandedBlockSamples())
                << file << " B=" << block;
            Grid transform = Grid::sparseFromDense(
                shape, bakeExactSamples(bvh, shape, SignMethod::WindingNumber), block, 3);
            EXPECT_EQ(band.flags(), transform.flags()) << file << " B=" << block;
            const std::vector<float> a = band.expandedBlockSamples(),
                                     b = transform.expandedBlockSamples();
            ASSERT_EQ(a.size(), b.size());
            for (size_t i = 0; i < a.size(); ++i)
                ASSERT_NEAR(a[i], b[i], 1e-5f * so.resolution * shape.voxelSize)
                    << file << " B=" << block << " sample " << i;
            EXPECT_LT(st.distanceQueries, shape.vertexCount()) << file;
            size_t in, out, surf;
            band.blockCounts(in, out, surf);
            if (block == 4 && std::string(file) == "bunny_npm.obj") {
                EXPECT_GT(in, 0u);
            }
        }
    }
}

// On a watertight mesh the exact bake evaluates the winding number only near the surface and
// carries the sign along rows elsewhere; it must agree with the winding number everywhere.
TEST(MeshBake, SignsCarriedAlongRowsMatchTheWindingNumber) {
    TriangleMesh mesh = loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/bunny_npm.obj");
    ASSERT_TRUE(isWatertight(mesh));
    MeshBvh bvh(mesh);
    WindingNumber winding(mesh);
    SampleOptions so;
    so.resolution = 28;
    so.kind = GridKind::Dense;
    GridShape s = gridShapeFor(mesh.bounds(), so);
    ExactBakeStats st;
    std::vector<float> d = bakeExactSamples(bvh, s, SignMethod::WindingNumber, 0, &st);
    size_t n = 0;
    for (int k = 0; k <= s.cells[2]; ++k)
        for (int j = 0; j <= s.cells[1]; ++j)
            for (int i = 0; i <= s.cells[0]; ++i, ++n)
                ASSERT_EQ(d[n]<0, winding.exact(s.origin + Vec3(i, j, k) * s.voxelSize)> 0.5)
                    << i << "," << j << "," << k;
    EXPECT_LT(st.signEvaluations, d.size() / 4);
    EXPECT_FALSE(isWatertight(loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/teapot.obj")));
}

// The bunny baked (exact, 128 cells, sparse) and rendered through the grid tracer, against
// Embree's first hits of the same primary rays: hit/miss agree except next to silhouettes, and
// depth is within one voxel (over the cosine to the normal) on the hits.
TEST(MeshBake, BakedBunnyRendersLikeRayCastTriangles) {
    TriangleMesh mesh = loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/bunny_npm.obj");
    MeshBakeOptions o;
    o.sampling.resolution = 128;
    auto grid = std::make_shared<const Grid>(bakeMesh(mesh, o).grid);
    Scene scene = sceneForObject(node::grid(grid), grid->surfaceBounds());
    const int W = 120, H = 90;
    scene.camera.width = W;
    scene.camera.height = H;
    Film film(W, H);
    render(planRender(scene), film);
    MeshBvh bvh(mesh);
    Camera cam(scene.camera);
    std::vector<float> truth(W * H);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) truth[y * W + x] = bvh.firstHit(cam.pixelRay(x, y)).t;
    auto hit = [&](const std::vector<float>& d, int x, int y) {
        return std::isfinite(d[std::clamp(y, 0, H - 1) * W + std::clamp(x, 0, W - 1)]);
    };
    const float h = grid->shape().voxelSize;
    int mismatches = 0, hits = 0, far = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            bool a = hit(film.depth, x, y), b = hit(truth, x, y);
            bool silhouette = false;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) silhouette |= hit(truth, x + dx, y + dy) != b;
            if (a != b && !silhouette) ++mismatches;
            if (!a || !b || silhouette) continue;
            ++hits;
            // The grid tracer's normal against the ray gives the slant of the surface.
            Vec3 n(film.normal[3 * (y * W + x)], film.normal[3 * (y * W + x) + 1],
                   film.normal[3 * (y * W + x) + 2]);
            float cosine = std::fabs(dot(n, cam.pixelRay(x, y).direction));
            far += std::fabs(film.depth[y * W + x] - truth[y * W + x]) > h / std::max(cosine, 0.2f);
        }
    EXPECT_GT(hits, W * H / 10);
    EXPECT_EQ(mismatches, 0);
    EXPECT_LE(far, hits / 100);  // grazing pixels where the normal is unreliable
}

}  // namespace
}  // namespace sdft

namespace sdft {
namespace {

// Two overlapping closed spheres in one mesh: watertight, winding number 2 in the overlap. The
// narrow-band bake carries the integer winding number through segment crossings; its signs must
// match the winding number's everywhere (the overlap is inside, not a parity flip).
TEST(MeshBake, IntegerWindingThroughSelfIntersectingShells) {
    TriangleMesh a = testing::icosphere(3), mesh = a;
    for (const auto& t : a.triangles) {
        uint32_t o = static_cast<uint32_t>(a.positions.size());
        mesh.triangles.push_back({t[0] + o, t[1] + o, t[2] + o});
    }
    for (Vec3 p : a.positions) mesh.positions.push_back(p + Vec3(0.7f, 0.1f, 0.05f));
    ASSERT_TRUE(isWatertight(mesh));
    MeshBvh bvh(mesh);
    WindingNumber winding(mesh);
    SampleOptions so;
    so.resolution = 32;
    GridShape s = gridShapeFor(mesh.bounds(), so);
    ExactBakeStats st;
    Grid g = bakeExactSparse(mesh, s, 4, 3, SignMethod::WindingNumber, 0, &st);
    GridView v = g.view();
    size_t checked = 0, overlap = 0;
    for (int k = 0; k <= s.cells[2]; ++k)
        for (int j = 0; j <= s.cells[1]; ++j)
            for (int i = 0; i <= s.cells[0]; ++i) {
                Vec3 p = s.origin + Vec3(i, j, k) * s.voxelSize;
                double w = winding.exact(p);
                if (std::fabs(w - std::round(w)) > 0.01) continue;  // on a surface
                ASSERT_EQ(v.vertex(i, j, k) < 0, w > 0.5) << i << "," << j << "," << k;
                ++checked;
                overlap += w > 1.5;
            }
    EXPECT_GT(overlap, 100u);
    EXPECT_GT(checked, 20000u);
    EXPECT_LT(st.signEvaluations, checked / 10);  // carried, not evaluated
}

// Every method gives the same grid on 1 and 2 threads (per-vertex random streams, slab-ordered
// seeding, owner-ordered scattering).
TEST(MeshBake, ThreadCountDoesNotChangeTheGrid) {
    TriangleMesh mesh = loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/teapot.obj");
    for (MeshBakeMethod method :
         {MeshBakeMethod::Exact, MeshBakeMethod::JumpFlood, MeshBakeMethod::Danielsson,
          MeshBakeMethod::SeparableEdt, MeshBakeMethod::Rtsdf}) {
        for (GridKind kind : {GridKind::Dense, GridKind::Sparse}) {
            MeshBakeOptions o;
            o.method = method;
            o.rtsdf.rays = 8;
            o.sampling.resolution = 32;
            o.sampling.kind = kind;
            o.sampling.threads = 1;
            Grid one = bakeMesh(mesh, o).grid;
            o.sampling.threads = 2;
            Grid two = bakeMesh(mesh, o).grid;
            const char* name = meshBakeMethodName(method);
            EXPECT_EQ(one.samples(), two.samples()) << name;
            EXPECT_EQ(one.flags(), two.flags()) << name;
            EXPECT_EQ(one.expandedBlockSamples(), two.expandedBlockSamples()) << name;
        }
    }
}

}  // namespace
}  // namespace sdft
