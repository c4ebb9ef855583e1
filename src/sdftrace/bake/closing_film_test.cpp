#include "sdftrace/bake/closing_film.h"

#include <gtest/gtest.h>

#include "sdftrace/bake/exact_bake.h"
#include "sdftrace/bake/winding_number.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/test_util.h"
#include "sdftrace/io/mesh_io.h"

namespace sdft {
namespace {

TriangleMesh load(const std::string& name) {
    return loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + name);
}

// The films close every open mesh (mesh + films is watertight) and leave a closed one alone.
TEST(ClosingFilm, ClosesTheRimOfOpenMeshes) {
    for (const char* name : {"elephant-with-holes.obj", "teapot.obj", "suzanne.obj"}) {
        TriangleMesh mesh = load(name);
        ClosingFilm film(mesh);
        EXPECT_FALSE(film.empty()) << name;
        EXPECT_GE(film.components(), 1u) << name;
        EXPECT_TRUE(isWatertight(film.closedMesh())) << name;
        EXPECT_EQ(film.closedMesh().triangles.size(),
                  mesh.triangles.size() + film.filmTriangles().size());
    }
    ClosingFilm closed(load("bunny_npm.obj"));
    EXPECT_TRUE(closed.empty());
    EXPECT_EQ(closed.gradientBound(Vec3(0.0f), Vec3(1.0f)), 0.0);
    // A lone triangle: its rim is one piece of three edges.
    TriangleMesh one;
    one.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
    one.triangles = {{0, 1, 2}};
    ClosingFilm cone(one);
    EXPECT_EQ(cone.components(), 1u);
    EXPECT_EQ(cone.filmTriangles().size(), 3u);
    EXPECT_TRUE(isWatertight(cone.closedMesh()));
}

// The winding number of mesh + films is an integer everywhere, and the mesh's own is that integer
// less the films' (exactly, and within fastError for the float sum).
TEST(ClosingFilm, MeshWindingIsTheClosedIntegerLessTheFilms) {
    for (const char* name : {"elephant-with-holes.obj", "teapot.obj"}) {
        TriangleMesh mesh = load(name);
        ClosingFilm film(mesh);
        WindingNumber open(mesh), closed(film.closedMesh());
        Bounds3 b = mesh.bounds().expanded(0.2f * maxComponent(mesh.bounds().extent()));
        testing::Rng rng(7);
        for (int n = 0; n < 200; ++n) {
            Vec3 p = rng.inBox(b.lo, b.hi);
            double W = closed.exact(p);
            ASSERT_NEAR(W, std::round(W), 1e-6) << name;
            double wF = film.winding(p);
            ASSERT_NEAR(open.exact(p), std::round(W) - wF, 1e-6) << name;
            ASSERT_NEAR(film.windingFast(p), wF, film.fastError()) << name;
        }
    }
}

// Away from the surface the mesh's winding number changes by at most the gradient bound times the
// step (up to its integer jumps across the mesh): the bound the carried signs rely on.
TEST(ClosingFilm, GradientBoundHoldsBetweenNearbyPoints) {
    for (const char* name : {"elephant-with-holes.obj", "teapot.obj"}) {
        TriangleMesh mesh = load(name);
        ClosingFilm film(mesh);
        WindingNumber open(mesh);
        Bounds3 b = mesh.bounds().expanded(0.2f * maxComponent(mesh.bounds().extent()));
        const float step = 0.02f * maxComponent(mesh.bounds().extent());
        testing::Rng rng(11);
        int checked = 0;
        double tightest = 0;  // the largest change over its bound
        for (int n = 0; n < 400; ++n) {
            Vec3 p = rng.inBox(b.lo, b.hi), q = p + rng.direction() * step;
            double g = film.gradientBound(min(p, q), max(p, q));
            if (!(g * step < 0.4)) continue;  // near the rim: no useful bound
            double change = open.exact(q) - open.exact(p);
            change -= std::round(change);
            ASSERT_LE(std::fabs(change), g * step + 1e-6) << name << " at " << n;
            ++checked;
            tightest = std::max(tightest, std::fabs(change) / (g * step));
        }
        EXPECT_GT(checked, 200) << name;
        // A bound, but not a vacuous one: some steps change by a good part of it (on the teapot;
        // the fields of the elephant's 106 holes partly cancel, which a bound cannot see).
        EXPECT_GT(tightest, std::string(name) == "teapot.obj" ? 0.2 : 0.005) << name;
    }
}

// About a centre in a ball no film meets, the films' winding number is its Taylor model's within
// the stated bound, and the model's gradient is the field's (central differences); the films
// near a box are those a brute-force scan finds.
TEST(ClosingFilm, TaylorModelBoundsTheFilmsWindingNumberInItsBall) {
    for (const char* name : {"elephant-with-holes.obj", "teapot.obj", "suzanne.obj"}) {
        TriangleMesh mesh = load(name);
        ClosingFilm film(mesh);
        const float size = maxComponent(mesh.bounds().extent());
        Bounds3 b = mesh.bounds().expanded(0.2f * size);
        testing::Rng rng(5);
        std::vector<uint32_t> near;
        int checked = 0, gradients = 0;
        double tightest = 0;
        for (int n = 0; n < 300; ++n) {
            const Vec3 c = rng.inBox(b.lo, b.hi);
            const float half = size * (n % 3 == 0 ? 0.005f : n % 3 == 1 ? 0.02f : 0.06f);
            film.trianglesNear(c - Vec3(half), c + Vec3(half), 0, near);
            // Through the loops' tree: exactly the film triangles whose boxes meet the box.
            std::vector<uint32_t> brute;
            for (size_t k = 0; k < film.filmTriangles().size(); ++k) {
                const CrossingTriangle& f = film.filmTriangles()[k];
                if (maxComponent(max(f.lo - (c + Vec3(half)), (c - Vec3(half)) - f.hi)) <= 0)
                    brute.push_back(static_cast<uint32_t>(k));
            }
            std::sort(near.begin(), near.end());
            ASSERT_EQ(near, brute) << name << " at " << n;
            const ClosingFilm::Taylor t = film.taylor(c, half);
            if (!near.empty() || !t.valid) continue;
            for (int k = 0; k < 8; ++k) {
                const Vec3 p = c + rng.direction() * (half * static_cast<float>(k) / 8);
                const double r = length(p - c);
                const double model = t.value + dot(t.gradient, p - c);
                const double bound = t.error + t.quadratic * r * r;
                const double off = std::fabs(film.winding(p) - model);
                ASSERT_LE(off, bound + 1e-6) << name << " at " << n << "," << k;
                tightest = std::max(tightest, off / bound);
                ++checked;
            }
            if (t.error < 2e-3f) {
                const float h = 1e-3f * size;
                for (int a = 0; a < 3; ++a) {
                    Vec3 e(0.0f);
                    e[a] = h;
                    const double fd = (film.winding(c + e) - film.winding(c - e)) / (2 * h);
                    EXPECT_NEAR(t.gradient[a], fd, 0.02 * length(t.gradient) + 2 * t.error / h)
                        << name << " at " << n;
                }
                ++gradients;
            }
        }
        EXPECT_GT(checked, 400) << name;
        // (The elephant's 106 holes leave a bounded remainder above that everywhere.)
        if (std::string(name) != "elephant-with-holes.obj") {
            EXPECT_GT(gradients, 10) << name;
        }
        EXPECT_GT(tightest, 0.01) << name;  // a bound, not a vacuous one
    }
}

// Carried through crossings and the gradient bound, the signs of both exact bakes of open meshes
// are the exact winding number's, with few evaluations from scratch.
TEST(ClosingFilm, CarriedSignsOfOpenMeshesMatchTheExactWindingNumber) {
    for (const char* name : {"elephant-with-holes.obj", "teapot.obj"}) {
        TriangleMesh mesh = load(name);
        MeshBvh bvh(mesh);
        WindingNumber reference(mesh);
        SampleOptions o;
        o.resolution = 26;
        GridShape shape = gridShapeFor(mesh.bounds(), o);
        ExactBakeStats denseStats, sparseStats;
        std::vector<float> dense =
            bakeExactSamples(bvh, shape, SignMethod::WindingNumber, 0, &denseStats);
        Grid sparse =
            bakeExactSparse(mesh, shape, 4, 3, SignMethod::WindingNumber, 0, &sparseStats);
        GridView v = sparse.view();
        size_t n = 0, checked = 0;
        for (int k = 0; k <= shape.cells[2]; ++k)
            for (int j = 0; j <= shape.cells[1]; ++j)
                for (int i = 0; i <= shape.cells[0]; ++i, ++n) {
                    double w = reference.exact(shape.origin + Vec3(i, j, k) * shape.voxelSize);
                    if (std::fabs(w - 0.5) < 1e-3) continue;
                    ASSERT_EQ(dense[n]<0, w> 0.5) << name << " " << i << "," << j << "," << k;
                    ASSERT_EQ(v.vertex(i, j, k) < 0, w > 0.5)
                        << name << " " << i << "," << j << "," << k;
                    ++checked;
                }
        EXPECT_GT(checked, dense.size() * 99 / 100) << name;
        EXPECT_LT(denseStats.signEvaluations, dense.size() / 10) << name;
        EXPECT_GT(denseStats.filmSums + sparseStats.filmSums, 0u) << name;
    }
}

}  // namespace
}  // namespace sdft
