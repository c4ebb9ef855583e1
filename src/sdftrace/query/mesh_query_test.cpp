#include "sdftrace/query/mesh_query.h"

#include <gtest/gtest.h>

#include <random>

#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/bake/test_meshes.h"
#include "sdftrace/bake/winding_number.h"
#include "sdftrace/core/error.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/io/mesh_io.h"
#include "sdftrace/query/triangle_closest.h"

namespace sdft {
namespace {
using namespace testing;

TriangleMesh load(const std::string& name) {
    return loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + name);
}

std::vector<Vec3d> doubles(const TriangleMesh& m, Vec3d offset = {}) {
    std::vector<Vec3d> v;
    for (Vec3 p : m.positions) v.push_back(toDouble(p) + offset);
    return v;
}

MeshQuery queryOf(const TriangleMesh& m, Vec3d offset = {}) {
    return MeshQuery(doubles(m, offset), m.triangles);
}

// Points uniform in the box grown by a quarter of its size, and points near the surface.
std::vector<Vec3d> testPoints(const MeshQuery& q, size_t n, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-0.25, 1.25);
    auto [lo, hi] = q.bounds();
    std::vector<Vec3d> pts;
    for (size_t i = 0; i < n; ++i)
        pts.push_back({lo.x + u(rng) * (hi.x - lo.x), lo.y + u(rng) * (hi.y - lo.y),
                       lo.z + u(rng) * (hi.z - lo.z)});
    std::normal_distribution<double> g(0, 0.003 * q.diagonal());
    for (size_t i = 0; i < n; ++i) {
        const auto& f = q.faces()[rng() % q.faces().size()];
        const Vec3d p = (q.vertices()[f[0]] + q.vertices()[f[1]] + q.vertices()[f[2]]) * (1 / 3.0);
        pts.push_back(p + Vec3d{g(rng), g(rng), g(rng)});
    }
    return pts;
}

// The reference: every face's exact closest point, in double.
double bruteDistance(const MeshQuery& q, Vec3d p) {
    double best = INFINITY;
    for (const auto& f : q.faces()) {
        const TriangleClosest c =
            closestOnTriangle(p, q.vertices()[f[0]], q.vertices()[f[1]], q.vertices()[f[2]]);
        best = std::min(best, norm(p - c.point));
    }
    return best;
}

// Distances equal the brute-force minimum within 1e-6 of the mesh's size; the closest point is
// the barycentric combination of its face's corners, at the reported distance.
TEST(MeshQuery, DistancesAndClosestPointsMatchBruteForce) {
    for (const char* name : {"suzanne.obj", "elephant-with-holes.obj", "bunny_npm.obj"}) {
        const TriangleMesh mesh = load(name);
        const MeshQuery q = queryOf(mesh);
        for (const Vec3d& p : testPoints(q, 150, 7)) {
            const MeshQuery::Closest c = q.closest(p);
            ASSERT_NEAR(c.distance, bruteDistance(q, p), 1e-6 * q.diagonal()) << name;
            const auto& f = q.faces()[c.face];
            const Vec3d on = q.vertices()[f[0]] * c.bary[0] + q.vertices()[f[1]] * c.bary[1] +
                             q.vertices()[f[2]] * c.bary[2];
            EXPECT_NEAR(norm(on - c.point), 0, 1e-12 * q.diagonal()) << name;
            EXPECT_NEAR(c.bary[0] + c.bary[1] + c.bary[2], 1, 1e-12);
            for (double b : c.bary) EXPECT_GE(b, -1e-12);
            EXPECT_NEAR(norm(p - c.point), c.distance, 1e-12 * q.diagonal());
        }
    }
}

// A mesh ten million times its size from the origin keeps its distances (kept relative to its
// centre), where float coordinates would have lost them.
TEST(MeshQuery, FarFromTheOriginKeepsItsPrecision) {
    const TriangleMesh mesh = torusMesh(1.0f, 0.3f, 48, 24);
    const Vec3d offset{2.5e7, -1.0e7, 3.0e7};
    const MeshQuery near = queryOf(mesh), far = queryOf(mesh, offset);
    for (const Vec3d& p : testPoints(near, 100, 3)) {
        const double d = near.closest(p).distance;
        EXPECT_NEAR(far.closest(p + offset).distance, d, 1e-6 * near.diagonal());
        EXPECT_EQ(far.inside(p + offset, MeshSign::Winding), near.inside(p, MeshSign::Winding));
    }
}

// On closed meshes every sign rule agrees with the exact winding number, away from the surface's
// rounding.
TEST(MeshQuery, SignsOfClosedMeshesMatchTheExactWindingNumber) {
    const std::vector<TriangleMesh> meshes = {load("bunny_npm.obj"), torusMesh(1.0f, 0.4f, 40, 20),
                                              boxMesh(Vec3(1.0f, 0.5f, 0.25f))};
    for (const TriangleMesh& mesh : meshes) {
        const MeshQuery q = queryOf(mesh);
        EXPECT_TRUE(q.watertight());
        const WindingNumber exact(mesh);
        size_t checked = 0;
        for (const Vec3d& p : testPoints(q, 300, 11)) {
            const MeshQuery::Closest c = q.closest(p);
            if (c.distance < 1e-6 * q.diagonal()) continue;
            const bool in = exact.exact(Vec3(p.x, p.y, p.z)) > 0.5;
            ASSERT_EQ(q.inside(p, MeshSign::Winding), in);
            ASSERT_EQ(q.inside(p, MeshSign::Parity), in);
            ASSERT_EQ(q.inside(p, MeshSign::PseudoNormal, &c), in);
            ASSERT_EQ(q.inside(p, MeshSign::PseudoNormal), in);
            EXPECT_NEAR(q.windingNumber(p), in ? 1.0 : 0.0, 1e-9);
            ++checked;
        }
        EXPECT_GT(checked, 590u);
    }
}

// On open scans the winding sign is the generalized winding number's (> 1/2 inside) and
// windingNumber() is that number.
TEST(MeshQuery, WindingOfOpenMeshesIsTheGeneralizedWindingNumber) {
    for (const char* name : {"elephant-with-holes.obj", "teapot.obj", "suzanne.obj"}) {
        const TriangleMesh mesh = load(name);
        const MeshQuery q = queryOf(mesh);
        EXPECT_FALSE(q.watertight()) << name;
        const WindingNumber exact(mesh);
        size_t checked = 0;
        for (const Vec3d& p : testPoints(q, 200, 5)) {
            const double w = exact.exact(Vec3(p.x, p.y, p.z));
            EXPECT_NEAR(q.windingNumber(p), w, 1e-3) << name;
            if (std::fabs(w - 0.5) < 1e-3) continue;
            ASSERT_EQ(q.inside(p, MeshSign::Winding), w > 0.5) << name;
            ++checked;
        }
        EXPECT_GT(checked, 390u) << name;
    }
}

// A CAD-like part: a box whose walls are 1 % of its size thick (an outer shell and an inner one
// facing inward), each face split into n x n squares, so that many coplanar faces and the far
// side of a wall lie within a point's first bound.
TriangleMesh thinWalledBox(int n) {
    TriangleMesh m;
    auto shell = [&](Vec3 lo, Vec3 hi, bool inward) {
        for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side) {
                const int u = (axis + 1) % 3, w = (axis + 2) % 3;
                const auto base = static_cast<uint32_t>(m.positions.size());
                for (int i = 0; i <= n; ++i)
                    for (int j = 0; j <= n; ++j) {
                        Vec3 p;
                        p[axis] = side ? hi[axis] : lo[axis];
                        p[u] = lo[u] + (hi[u] - lo[u]) * static_cast<float>(i) / n;
                        p[w] = lo[w] + (hi[w] - lo[w]) * static_cast<float>(j) / n;
                        m.positions.push_back(p);
                    }
                // Outward where (side == 1) matches the axes' handedness, flipped for the inner.
                const bool flip = (side == 0) != inward;
                for (int i = 0; i < n; ++i)
                    for (int j = 0; j < n; ++j) {
                        const uint32_t a = base + i * (n + 1) + j, b = a + (n + 1), c = b + 1,
                                       d = a + 1;
                        if (flip) {
                            m.triangles.push_back({a, c, b});
                            m.triangles.push_back({a, d, c});
                        } else {
                            m.triangles.push_back({a, b, c});
                            m.triangles.push_back({a, c, d});
                        }
                    }
            }
    };
    shell(Vec3(0, 0, 0), Vec3(1, 0.6f, 0.4f), false);
    shell(Vec3(0.01f, 0.01f, 0.01f), Vec3(0.99f, 0.59f, 0.39f), true);
    return m;
}

// The batch walks points in Morton order with neighbour bounds: the same answers as one at a
// time, in float and in double, for any subset of outputs.
// Clusters of neighbours share one candidate search (triangle_lanes.h), or search one by one
// where candidates are many (the fine sphere, points far away); a closed mesh's signs are carried
// across crossings counted on the segment between neighbours (two overlapping boxes with a shared
// face: winding 2 where they overlap), and so is an open mesh's W, closed by its films.
TEST(MeshQuery, BatchesAnswerAsSinglePointsDo) {
    TriangleMesh boxes = boxMesh(Vec3(1.0f, 0.5f, 0.5f));
    const TriangleMesh second = boxMesh(Vec3(0.5f, 0.5f, 1.0f));
    for (const auto& f : second.triangles)
        boxes.triangles.push_back({f[0] + 8, f[1] + 8, f[2] + 8});
    boxes.positions.insert(boxes.positions.end(), second.positions.begin(), second.positions.end());
    const std::vector<std::pair<std::string, TriangleMesh>> meshes = {
        {"suzanne", load("suzanne.obj")},  // open, 4 holes: W carried, films' Taylor models
        {"teapot", load("teapot.obj")},    // open, 6 holes
        {"elephant", load("elephant-with-holes.obj")},  // open, 106 holes: the mesh's own sums
        {"bunny_npm", load("bunny_npm.obj")},           // closed: signs carried
        {"boxes", boxes},
        {"thin-walled box", thinWalledBox(12)},  // many candidates: filtered by group boxes
        {"icosphere 5", icosphere(5)}};
    for (const auto& [name, mesh] : meshes) {
        const MeshQuery q = queryOf(mesh);
        std::vector<Vec3d> pts = testPoints(q, 2000, 13);
        std::mt19937 rng(17);
        std::uniform_real_distribution<double> far(-100, 100);
        for (int k = 0; k < 300; ++k)
            pts.push_back(Vec3d{far(rng), far(rng), far(rng)} * q.diagonal());
        const size_t n = pts.size();
        std::vector<double> xyz;
        for (const Vec3d& p : pts) xyz.insert(xyz.end(), {p.x, p.y, p.z});
        std::vector<float> xyzf(xyz.begin(), xyz.end());
        for (MeshSign sign : {MeshSign::Winding, MeshSign::Parity, MeshSign::PseudoNormal}) {
            // Parity rays and pseudonormals are fooled by overlapping shells (the documented
            // limits of those signs); the winding number is not.
            if (name == "boxes" && sign != MeshSign::Winding) continue;
            std::vector<double> d(n), cp(3 * n), bary(3 * n);
            std::vector<int64_t> face(n);
            std::unique_ptr<bool[]> in(new bool[n]);
            MeshQuery::PointOutputs out{d.data(),    cp.data(), face.data(),
                                        bary.data(), nullptr,   in.get()};
            q.queryPoints(xyz.data(), n, out, {true, sign, ""});
            std::vector<float> df(n);
            q.queryPoints(xyzf.data(), n, {df.data()}, {true, sign, ""});
            for (size_t i = 0; i < n; ++i) {
                const MeshQuery::Closest c = q.closest(pts[i]);
                const bool inside = q.inside(pts[i], sign, &c);
                // Float searches may break a near tie differently: within their rounding.
                ASSERT_NEAR(std::fabs(d[i]), c.distance, 1e-6 * q.diagonal()) << name;
                ASSERT_EQ(in[i], inside) << name << " point " << i;
                ASSERT_EQ(d[i] < 0, inside && c.distance > 0);
                // Float points round each coordinate by up to 2^-24 of it (for far points, of
                // about the distance), and the float answer rounds as much again.
                ASSERT_NEAR(df[i], d[i], 1e-6 * q.diagonal() + 3e-7 * std::fabs(d[i]));
                const Vec3d on = q.vertices()[q.faces()[face[i]][0]] * bary[3 * i] +
                                 q.vertices()[q.faces()[face[i]][1]] * bary[3 * i + 1] +
                                 q.vertices()[q.faces()[face[i]][2]] * bary[3 * i + 2];
                ASSERT_NEAR(norm(on - Vec3d{cp[3 * i], cp[3 * i + 1], cp[3 * i + 2]}), 0,
                            1e-9 * q.diagonal());
            }
        }
    }
}

// Ray casts against a brute-force double intersection of every face (Moller-Trumbore), refined
// in double and as Embree answers them in float.
TEST(MeshQuery, RayCastsMatchBruteForce) {
    const TriangleMesh mesh = load("bunny_npm.obj");
    const MeshQuery q = queryOf(mesh);
    std::mt19937 rng(3);
    std::normal_distribution<double> g(0, 1);
    size_t hits = 0;
    for (const Vec3d& o : testPoints(q, 150, 17)) {
        const Vec3d dir{g(rng), g(rng), g(rng)};
        double best = INFINITY;
        uint32_t bestFace = UINT32_MAX;
        for (size_t f = 0; f < q.faces().size(); ++f) {
            const Vec3d a = q.vertices()[q.faces()[f][0]], b = q.vertices()[q.faces()[f][1]],
                        c = q.vertices()[q.faces()[f][2]];
            const Vec3d e1 = b - a, e2 = c - a, pv = cross(dir, e2);
            const double det = dot(e1, pv);
            if (det == 0) continue;
            const Vec3d tv = o - a;
            const double u = dot(tv, pv) / det;
            const Vec3d qv = cross(tv, e1);
            const double v = dot(dir, qv) / det, t = dot(e2, qv) / det;
            if (u >= 0 && v >= 0 && u + v <= 1 && t > 0 && t < best) best = t, bestFace = f;
        }
        // Refined in double (double rays), or Embree's float answer (float rays).
        for (const bool refine : {true, false}) {
            const MeshQuery::Hit h = q.rayCast(o, dir, INFINITY, refine);
            if (bestFace == UINT32_MAX) {
                EXPECT_FALSE(std::isfinite(h.t));
                continue;
            }
            hits += refine;
            ASSERT_TRUE(std::isfinite(h.t));
            EXPECT_NEAR(h.t * norm(dir), best * norm(dir), 1e-5 * q.diagonal());
            const auto& f = q.faces()[h.face];
            const Vec3d a = q.vertices()[f[0]], b = q.vertices()[f[1]], c = q.vertices()[f[2]];
            const Vec3d x = a * (1 - h.u - h.v) + b * h.u + c * h.v;
            EXPECT_NEAR(norm(x - (o + dir * h.t)), 0, 1e-5 * q.diagonal());
            EXPECT_NEAR(norm(h.normal), 1, refine ? 1e-12 : 1e-6);
            const Vec3d n = cross(b - a, c - a);
            EXPECT_GT(dot(h.normal, n) / norm(n), 1 - 1e-5);
            // t_max cuts it off.
            EXPECT_FALSE(std::isfinite(q.rayCast(o, dir, best * 0.99, refine).t));
        }
    }
    EXPECT_GT(hits, 50u);
}

// A zero-area face counts as its edges; a bad mesh or point is an InputError.
TEST(MeshQuery, DegenerateFacesAndBadInput) {
    std::vector<Vec3d> v = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}};
    const MeshQuery q(v, {{0, 1, 2}});  // a segment from (0,0,0) to (2,0,0)
    EXPECT_NEAR(q.closest({1, 1, 0}).distance, 1, 1e-12);
    EXPECT_NEAR(q.closest({3, 0, 0}).distance, 1, 1e-12);
    EXPECT_THROW(MeshQuery(v, {}), InputError);
    EXPECT_THROW(MeshQuery(v, {{0, 1, 4}}), InputError);
    v[3].y = NAN;
    EXPECT_THROW(MeshQuery(v, {{0, 1, 3}}), InputError);
    const double bad[6] = {0, 0, 0, 1, NAN, 0};
    double d[2];
    EXPECT_THROW(q.queryPoints(bad, 2, {d}, {}), InputError);
}

}  // namespace
}  // namespace sdft
