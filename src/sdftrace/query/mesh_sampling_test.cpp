#include "sdftrace/query/mesh_sampling.h"

#include <gtest/gtest.h>

#include "sdftrace/bake/test_meshes.h"
#include "sdftrace/core/error.h"

namespace sdft {
namespace {
using namespace testing;

MeshQuery queryOf(const TriangleMesh& m) {
    std::vector<Vec3d> v;
    for (Vec3 p : m.positions) v.push_back(toDouble(p));
    return MeshQuery(v, m.triangles);
}

// Surface samples lie on their faces, with the faces' normals, spread by area, reproducibly.
TEST(MeshSampling, SurfaceSamplesLieOnTheirFacesByArea) {
    const TriangleMesh box = boxMesh(Vec3(2.0f, 1.0f, 0.5f));  // half-sizes: faces of 2, 4, 8
    const MeshQuery q = queryOf(box);
    const size_t n = 60000;
    std::vector<double> p(3 * n), nrm(3 * n);
    std::vector<int64_t> face(n);
    sampleSurface(q, n, 42, p.data(), nrm.data(), face.data());
    double onX = 0;
    for (size_t i = 0; i < n; ++i) {
        const Vec3d x{p[3 * i], p[3 * i + 1], p[3 * i + 2]};
        const MeshQuery::Closest c = q.closest(x);
        ASSERT_LT(c.distance, 1e-12);
        const auto& f = q.faces()[face[i]];
        const Vec3d a = q.vertices()[f[0]], b = q.vertices()[f[1]], cc = q.vertices()[f[2]];
        const Vec3d nn = cross(b - a, cc - a);
        ASSERT_NEAR(std::fabs(dot(x - a, nn)), 0, 1e-9);
        ASSERT_NEAR(nrm[3 * i] * nn.x + nrm[3 * i + 1] * nn.y + nrm[3 * i + 2] * nn.z, norm(nn),
                    1e-9);
        if (std::fabs(std::fabs(x.x) - 2) < 1e-9) ++onX;
    }
    // The two x faces (2 x 1 each) hold 4 of the total area 2 * (2 + 4 + 8) = 28 (5 sigma: 0.007).
    EXPECT_NEAR(onX / n, 4.0 / 28.0, 0.007);
    std::vector<double> again(3 * n);
    sampleSurface(q, n, 42, again.data(), static_cast<double*>(nullptr), nullptr);
    EXPECT_EQ(again, p);
    sampleSurface(q, n, 43, again.data(), static_cast<double*>(nullptr), nullptr);
    EXPECT_NE(again, p);
}

// Near-surface samples are surface points moved by Gaussians of the given widths; volume samples
// fill their box.
TEST(MeshSampling, NearSurfaceWidthsAndVolumeBounds) {
    const MeshQuery q = queryOf(icosphere(4));
    const size_t n = 40000;
    std::vector<float> p(3 * n);
    sampleNearSurface(q, n, {0.1, 0.01}, 7, p.data());
    double sum[2] = {0, 0};
    for (size_t i = 0; i < n; ++i) {
        const Vec3d x{p[3 * i], p[3 * i + 1], p[3 * i + 2]};
        const double d = q.closest(x).distance;
        sum[i % 2] += d * d;
    }
    // The distance to the (nearly flat) surface is about the normal component: sigma^2 on average.
    EXPECT_NEAR(std::sqrt(sum[0] / (n / 2)), 0.1, 0.01);
    EXPECT_NEAR(std::sqrt(sum[1] / (n / 2)), 0.01, 0.001);
    EXPECT_THROW(sampleNearSurface(q, 10, {}, 7, p.data()), InputError);
    EXPECT_THROW(sampleNearSurface(q, 10, {-1.0}, 7, p.data()), InputError);
    std::vector<double> v(3 * n);
    sampleVolume(n, {-1, 0, 2}, {1, 0.5, 6}, 9, v.data());
    double mean[3] = {0, 0, 0};
    for (size_t i = 0; i < n; ++i) {
        ASSERT_TRUE(v[3 * i] >= -1 && v[3 * i] <= 1 && v[3 * i + 1] >= 0 && v[3 * i + 1] <= 0.5 &&
                    v[3 * i + 2] >= 2 && v[3 * i + 2] <= 6);
        for (int a = 0; a < 3; ++a) mean[a] += v[3 * i + a] / n;
    }
    EXPECT_NEAR(mean[0], 0, 0.02);
    EXPECT_NEAR(mean[2], 4, 0.04);
}

}  // namespace
}  // namespace sdft
