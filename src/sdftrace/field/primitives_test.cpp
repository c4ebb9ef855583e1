// Each primitive against an independent reference: its surface sampled densely (by bisection of
// its inside/outside predicate along rays, or parametrically) gives the true distance to within the
// sampling spacing. Exact primitives must match it; bounds must not exceed it; signs must match the
// inside predicate everywhere.
#include <gtest/gtest.h>

#include <functional>

#include "sdftrace/field/node.h"
#include "sdftrace/field/test_util.h"

namespace sdft {
namespace {

using Inside = std::function<bool(Vec3)>;

// Surface points of a shape star-shaped about the origin: bisection of `inside` along random rays.
std::vector<Vec3> sampleStarShaped(const Inside& inside, float reach, int count, uint32_t seed) {
    testing::Rng rng(seed);
    std::vector<Vec3> pts;
    for (int i = 0; i < count; ++i) {
        Vec3 u = rng.direction();
        float lo = 0, hi = reach;
        for (int it = 0; it < 40; ++it) {
            float mid = 0.5f * (lo + hi);
            (inside(u * mid) ? lo : hi) = mid;
        }
        pts.push_back(u * (0.5f * (lo + hi)));
    }
    return pts;
}

float nearest(const std::vector<Vec3>& pts, Vec3 p) {
    float best = 1e30f;
    for (const Vec3& q : pts) {
        Vec3 d = p - q;
        best = std::fmin(best, dot(d, d));
    }
    return std::sqrt(best);
}

struct Case {
    const char* name;
    NodePtr node;
    Inside inside;
    std::vector<Vec3> surface;
    bool exact;
    float tolerance;  // sampling spacing allowance
};

void checkAgainstSamples(const Case& c, float queryHalfSize, uint32_t seed) {
    testing::Rng rng(seed);
    int checked = 0;
    for (int i = 0; i < 300; ++i) {
        Vec3 p = rng.inCube(queryHalfSize);
        float f = evalTree(*c.node, p);
        float d = nearest(c.surface, p);  // >= true distance, within tolerance of it
        bool in = c.inside(p);
        if (d > c.tolerance) {  // sign is only well defined away from the surface
            EXPECT_EQ(f < 0, in) << c.name << " sign at " << p.x << "," << p.y << "," << p.z;
        }
        EXPECT_LE(std::fabs(f), d + 1e-4f)
            << c.name << " exceeds the distance at " << p.x << "," << p.y << "," << p.z;
        if (c.exact) {
            EXPECT_GE(std::fabs(f), d - c.tolerance)
                << c.name << " at " << p.x << "," << p.y << "," << p.z;
        }
        ++checked;
    }
    EXPECT_EQ(checked, 300);
}

TEST(Primitives, MatchSampledDistances) {
    const int n = 60000;
    std::vector<Case> cases;
    auto star = [&](const char* name, NodePtr node, Inside in, float reach, bool exact) {
        cases.push_back({name, node, in, sampleStarShaped(in, reach, n, 7), exact, 0.035f});
    };
    star(
        "sphere", node::sphere(0.8f), [](Vec3 p) { return length(p) < 0.8f; }, 2, true);
    star(
        "box", node::box({0.5f, 0.3f, 0.7f}),
        [](Vec3 p) {
            return std::fabs(p.x) < 0.5f && std::fabs(p.y) < 0.3f && std::fabs(p.z) < 0.7f;
        },
        2, true);
    star(
        "round_box", node::roundBox({0.6f, 0.4f, 0.5f}, 0.15f),
        [](Vec3 p) {
            Vec3 q = max(abs(p) - Vec3(0.45f, 0.25f, 0.35f), 0.0f);
            return length(q) < 0.15f;
        },
        2, true);
    star(
        "cylinder", node::cylinder(0.5f, 0.4f),
        [](Vec3 p) { return p.x * p.x + p.z * p.z < 0.25f && std::fabs(p.y) < 0.4f; }, 2, true);
    star(
        "cone", node::cone(0.5f, 1.0f),
        [](Vec3 p) {
            // radius shrinks linearly from 0.5 at y = -0.5 to 0 at y = +0.5
            float r = 0.5f * (0.5f - p.y);
            return p.y > -0.5f && p.y < 0.5f && std::sqrt(p.x * p.x + p.z * p.z) < r;
        },
        2, true);
    star(
        "ellipsoid", node::ellipsoid({0.8f, 0.4f, 0.5f}),
        [](Vec3 p) { return length(p / Vec3(0.8f, 0.4f, 0.5f)) < 1; }, 2, false);
    star(
        "octahedron", node::octahedron(0.7f),
        [](Vec3 p) { return std::fabs(p.x) + std::fabs(p.y) + std::fabs(p.z) < 0.7f; }, 2, false);
    {
        const float phi = 1.618033988749895f;
        Vec3 normals[6] = {{0, 1, phi},  {0, 1, -phi}, {1, phi, 0},
                           {1, -phi, 0}, {phi, 0, 1},  {-phi, 0, 1}};
        star(
            "dodecahedron", node::dodecahedron(0.5f),
            [normals](Vec3 p) {
                for (Vec3 nn : normals)
                    if (std::fabs(dot(normalize(nn), p)) >= 0.5f) return false;
                return true;
            },
            2, false);
    }
    {
        std::vector<node::Blob> list = {{{0, 0, 0}, 0.8f, 1.0f}, {{0.3f, 0.1f, 0}, 0.6f, 1.0f}};
        star(
            "blobs", node::blobs(list, 0.5f),
            [list](Vec3 p) {
                float density = 0;
                for (const auto& b : list) {
                    float u = length(p - b.center) / b.radius;
                    if (u < 1) density += b.strength * (1 - u * u) * (1 - u * u) * (1 - u * u);
                }
                return density > 0.5f;
            },
            2, false);
    }
    // Not star-shaped: parametric samples.
    {
        std::vector<Vec3> pts;
        for (int i = 0; i < 400; ++i)
            for (int j = 0; j < 150; ++j) {
                float u = 6.2831853f * i / 400, v = 6.2831853f * j / 150;
                float rr = 0.6f + 0.2f * std::cos(v);
                pts.push_back({rr * std::cos(u), 0.2f * std::sin(v), rr * std::sin(u)});
            }
        cases.push_back({"torus", node::torus(0.6f, 0.2f),
                         [](Vec3 p) {
                             float q = std::sqrt(p.x * p.x + p.z * p.z) - 0.6f;
                             return q * q + p.y * p.y < 0.04f;
                         },
                         pts, true, 0.02f});
    }
    {
        Vec3 a(-0.5f, 0, 0), b(0.5f, 0.3f, 0);
        std::vector<Vec3> pts;
        testing::Rng rng(3);
        for (int i = 0; i < n; ++i) {
            // Points on the capsule: a point on the segment plus r in a direction normal to it,
            // or on the end caps.
            float t = rng.uniform(-0.3f, 1.3f);
            Vec3 c = a + (b - a) * clampf(t, 0, 1);
            Vec3 dir = rng.direction();
            if (t >= 0 && t <= 1)
                dir = normalize(dir - normalize(b - a) * dot(dir, normalize(b - a)));
            pts.push_back(c + dir * 0.25f);
        }
        cases.push_back({"capsule", node::capsule(a, b, 0.25f),
                         [a, b](Vec3 p) {
                             float h = clampf(dot(p - a, b - a) / dot(b - a, b - a), 0, 1);
                             return length(p - a - (b - a) * h) < 0.25f;
                         },
                         pts, true, 0.04f});
    }
    uint32_t seed = 100;
    for (const Case& c : cases) checkAgainstSamples(c, 1.3f, seed++);
}

TEST(Primitives, PlaneIsSignedDistanceToTheHalfSpace) {
    NodePtr p = node::plane({0, 2, 0}, 0.5f);  // y * 1 + 0.5 <= 0 is solid
    testing::Rng rng(1);
    for (int i = 0; i < 100; ++i) {
        Vec3 q = rng.inCube(5);
        EXPECT_NEAR(evalTree(*p, q), q.y + 0.5f, 1e-5f);
    }
}

TEST(Primitives, BoundsContainTheSurface) {
    // Every point where a primitive's value is negative lies inside its bounds.
    testing::Rng rng(11);
    std::vector<NodePtr> nodes = {node::sphere(0.5f),
                                  node::box({0.3f, 0.4f, 0.5f}),
                                  node::torus(0.6f, 0.2f),
                                  node::cone(0.4f, 1.0f),
                                  node::dodecahedron(0.5f),
                                  node::ellipsoid({0.7f, 0.2f, 0.3f}),
                                  node::capsule({0, 0, 0}, {0.5f, 0.5f, 0}, 0.2f),
                                  node::octahedron(0.6f)};
    for (const NodePtr& n : nodes) {
        Bounds3 b = nodeBounds(*n);
        for (int i = 0; i < 20000; ++i) {
            Vec3 p = rng.inCube(1.2f);
            if (evalTree(*n, p) < 0) {
                ASSERT_TRUE(b.contains(p)) << nodeKindName(n->kind);
            }
        }
    }
}

// One example of each row of the primitive table; a new row without one fails here.
NodePtr examplePrimitive(NodeKind kind) {
    switch (kind) {
        case NodeKind::Sphere:
            return node::sphere(0.5f);
        case NodeKind::Box:
            return node::box({0.3f, 0.4f, 0.5f});
        case NodeKind::RoundBox:
            return node::roundBox({0.3f, 0.4f, 0.5f}, 0.1f);
        case NodeKind::Torus:
            return node::torus(0.6f, 0.2f);
        case NodeKind::Capsule:
            return node::capsule({0, 0, 0}, {0.5f, 0.5f, 0}, 0.2f);
        case NodeKind::Cylinder:
            return node::cylinder(0.4f, 0.6f);
        case NodeKind::Cone:
            return node::cone(0.4f, 1.0f);
        case NodeKind::Plane:
            return node::plane({0, 1, 0}, 0.2f);
        case NodeKind::Ellipsoid:
            return node::ellipsoid({0.7f, 0.2f, 0.3f});
        case NodeKind::Octahedron:
            return node::octahedron(0.6f);
        case NodeKind::Dodecahedron:
            return node::dodecahedron(0.5f);
        case NodeKind::Blobs:
            return node::blobs({{{-0.2f, 0, 0}, 0.5f, 1}, {{0.25f, 0.1f, 0}, 0.4f, 1}}, 0.5f);
        default:
            return nullptr;
    }
}

float distanceToBox(const Bounds3& b, Vec3 p) {
    const Vec3 d = max(max(b.lo - p, p - b.hi), 0.0f);
    return length(d);
}

// The table's flags hold for every row: negative values lie in the bounds, a row that dominates
// its bounds is at least the distance to them outside, and a convex row's inside is convex.
TEST(PrimitiveTable, FlagsHoldForEveryRow) {
    struct Row {
        NodeKind kind;
        const char* name;
        bool convex, dominates;
    };
    const Row rows[] = {
#define SDFT_PRIMITIVE_ROW(Kind, name, eval, bounds, convex, dominates) \
    {NodeKind::Kind, name, convex, dominates},
        SDFT_PRIMITIVES(SDFT_PRIMITIVE_ROW)
#undef SDFT_PRIMITIVE_ROW
    };
    testing::Rng rng(23);
    for (const Row& row : rows) {
        const NodePtr n = examplePrimitive(row.kind);
        ASSERT_NE(n, nullptr) << row.name << ": add an example";
        EXPECT_STREQ(nodeKindName(row.kind), row.name);
        EXPECT_EQ(isConvex(*n), row.convex) << row.name;
        EXPECT_EQ(dominatesBounds(*n), row.dominates) << row.name;
        EXPECT_EQ(lipschitzBound(*n), 1.0f) << row.name;
        const Bounds3 b = nodeBounds(*n);
        std::vector<Vec3> inside;
        for (int i = 0; i < 20000; ++i) {
            const Vec3 p = rng.inCube(1.5f);
            const float f = evalTree(*n, p);
            if (f < 0) {
                ASSERT_TRUE(b.contains(p)) << row.name;
                inside.push_back(p);
            }
            if (row.dominates && !b.contains(p)) {
                ASSERT_GE(f, distanceToBox(b, p) - 1e-4f) << row.name;
            }
        }
        ASSERT_GT(inside.size(), 50u) << row.name;
        if (!row.convex) continue;
        for (size_t i = 0; i + 1 < inside.size(); i += 2) {
            const Vec3 mid = (inside[i] + inside[i + 1]) * 0.5f;
            ASSERT_LE(evalTree(*n, mid), 1e-5f) << row.name << ": not convex";
        }
    }
}

}  // namespace
}  // namespace sdft
