// The exact bake: closest points against brute force, and baked grids against meshes whose SDF is
// known in closed form (a box; a finely tessellated sphere, within its tessellation gap).
#include "sdftrace/bake/exact_bake.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "sdftrace/bake/closest_point.h"
#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/bake/test_meshes.h"
#include "sdftrace/bake/winding_number.h"
#include "sdftrace/field/primitives.h"
#include "sdftrace/field/test_util.h"
#include "sdftrace/io/mesh_io.h"

namespace sdft {
namespace {

TEST(ClosestPoint, MatchesDenseSamplingOfTheTriangle) {
    testing::Rng rng(1);
    for (int n = 0; n < 200; ++n) {
        Vec3 a = rng.inCube(1), b = rng.inCube(1), c = rng.inCube(1), p = rng.inCube(2);
        float d = length(p - closestPointOnTriangle(p, a, b, c));
        float best = 1e30f;
        const int N = 300;
        for (int i = 0; i <= N; ++i)
            for (int j = 0; i + j <= N; ++j) {
                float u = static_cast<float>(i) / N, v = static_cast<float>(j) / N;
                best = std::min(best, length(p - (a + (b - a) * u + (c - a) * v)));
            }
        EXPECT_LE(d, best + 1e-5f);
        EXPECT_GE(d, best - 0.02f);  // sampling spacing
    }
}

TEST(MeshBvh, ClosestDistanceEqualsBruteForceOnTheBunny) {
    MeshReport r;
    TriangleMesh mesh = loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/bunny_npm.obj", &r);
    MeshBvh bvh(mesh);
    Bounds3 b = mesh.bounds().expanded(0.3f * maxComponent(mesh.bounds().extent()));
    testing::Rng rng(2);
    for (int i = 0; i < 300; ++i) {
        Vec3 p = rng.inBox(b.lo, b.hi);
        float brute = 1e30f;
        for (const auto& t : mesh.triangles) {
            Vec3 q = closestPointOnTriangle(p, mesh.positions[t[0]], mesh.positions[t[1]],
                                            mesh.positions[t[2]]);
            brute = std::min(brute, length(p - q));
        }
        ASSERT_NEAR(bvh.closestDistance(p), brute, 1e-6f * (1 + brute));
    }
}

TEST(ExactBake, BoxMeshGivesTheBoxSdfToFloatRounding) {
    Vec3 half(0.5f, 0.3f, 0.7f);
    SampleOptions o;
    o.resolution = 32;
    o.kind = GridKind::Dense;
    MeshBakeOptions bake;
    bake.sampling = o;
    Grid g = bakeMesh(testing::boxMesh(half), bake).grid;
    GridView v = g.view();
    const GridShape& s = g.shape();
    float k[3] = {half.x, half.y, half.z};
    int inside = 0;
    for (int kk = 0; kk <= s.cells[2]; ++kk)
        for (int j = 0; j <= s.cells[1]; ++j)
            for (int i = 0; i <= s.cells[0]; ++i) {
                Vec3 p = s.origin + Vec3(i, j, kk) * s.voxelSize;
                float exact = prim::box(p, k);
                ASSERT_NEAR(v.vertex(i, j, kk), exact, 2e-6f) << i << "," << j << "," << kk;
                inside += exact < 0;
            }
    EXPECT_GT(inside, 1000);
}

TEST(ExactBake, TessellatedSphereWithinItsTessellationGap) {
    TriangleMesh sphere = testing::icosphere(4);  // 5,120 triangles
    // The polyhedron lies between radius cos(half the largest edge angle) and 1.
    float gap = 0;
    for (auto [a, b, c] : sphere.triangles)
        gap = std::max(
            gap,
            1 - length((sphere.positions[a] + sphere.positions[b] + sphere.positions[c]) / 3.0f));
    SampleOptions o;
    o.resolution = 40;
    MeshBakeOptions bake;
    bake.sampling = o;
    Grid g = bakeMesh(sphere, bake).grid;  // exact, sparse, band 3
    GridView v = g.view();
    testing::Rng rng(3);
    int checked = 0;
    for (int i = 0; i < 5000; ++i) {
        Vec3 p = rng.inCube(1.2f);
        float exact = length(p) - 1;
        float baked = v.interpolate(p);
        if (std::fabs(exact) > 2 * gap) {
            ASSERT_EQ(baked < 0, exact < 0) << p.x << "," << p.y << "," << p.z;
        }
        // Near the surface (in the band) the samples are exact distances to the polyhedron;
        // interpolation adds at most half a cell diagonal of error.
        if (std::fabs(exact) < 2 * g.shape().voxelSize) {
            EXPECT_NEAR(baked, exact, gap + 0.87f * g.shape().voxelSize);
            ++checked;
        }
    }
    EXPECT_GT(checked, 200);
    size_t in, out, surf;
    g.blockCounts(in, out, surf);
    EXPECT_GT(in, 0u);  // the inside is marked inside far from the surface
}

// On an open mesh (the elephant with holes cut out) the winding-number sign follows the exact
// winding number everywhere it is clear of 1/2; ray parity does not.
TEST(ExactBake, WindingNumberSignsOpenMeshesWhereParityFails) {
    TriangleMesh mesh =
        loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/elephant-with-holes.obj");
    MeshBvh bvh(mesh);
    WindingNumber reference(mesh);
    SampleOptions o;
    o.resolution = 24;
    GridShape shape = gridShapeFor(mesh.bounds(), o);
    std::vector<float> winding = bakeExactSamples(bvh, shape, SignMethod::WindingNumber);
    std::vector<float> parity = bakeExactSamples(bvh, shape, SignMethod::RayParity);
    int clear = 0, windingWrong = 0, parityWrong = 0;
    size_t n = 0;
    for (int k = 0; k <= shape.cells[2]; ++k)
        for (int j = 0; j <= shape.cells[1]; ++j)
            for (int i = 0; i <= shape.cells[0]; ++i, ++n) {
                double w = reference.exact(shape.origin + Vec3(i, j, k) * shape.voxelSize);
                if (std::fabs(w - 0.5) < 0.1) continue;
                ++clear;
                windingWrong += (winding[n] < 0) != (w > 0.5);
                parityWrong += (parity[n] < 0) != (w > 0.5);
            }
    EXPECT_GT(clear, 5000);
    EXPECT_EQ(windingWrong, 0);
    EXPECT_GT(parityWrong, 0);  // the failure the winding number is for
}

}  // namespace
}  // namespace sdft
