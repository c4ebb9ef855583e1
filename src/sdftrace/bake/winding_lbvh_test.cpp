// The dipole tree over the LBVH (winding_lbvh.h): its moments are the mesh's, every node's sphere
// holds its triangles, and its winding numbers match the exact sum and the median-split tree's
// signs, on a closed, an open and a thin mesh.
#include "sdftrace/bake/winding_lbvh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "sdftrace/bake/winding_number.h"
#include "sdftrace/io/mesh_io.h"

namespace sdft {
namespace {

TriangleMesh load(const std::string& name) {
    return loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + name);
}

double distance(Vec3 p, const WindingNode& n) {
    const double dx = p.x - n.cx, dy = p.y - n.cy, dz = p.z - n.cz;
    return std::sqrt(dx * dx + dy * dy + dz * dz);
}

// Area and dipole of the root are the sums over the triangles; each triangle is one leaf, in key
// order; each node's box and sphere hold the corners of every triangle below it.
TEST(LbvhWinding, MomentsAndBoundsAreTheMeshs) {
    const TriangleMesh mesh = load("suzanne.obj");
    const Lbvh lbvh(mesh);
    const LbvhWinding w(lbvh.view());
    const int n = static_cast<int>(mesh.triangles.size());
    ASSERT_EQ(w.nodes().size(), 2 * mesh.triangles.size() - 1);
    double area = 0, nx = 0, ny = 0, nz = 0;
    for (int j = 0; j < n; ++j) {
        const WindingNode& leaf = w.nodes()[static_cast<size_t>(n - 1 + j)];
        EXPECT_EQ(leaf.first, j);
        EXPECT_EQ(leaf.count, 1);
        EXPECT_EQ(leaf.left, -1);
        area += leaf.area, nx += leaf.nx, ny += leaf.ny, nz += leaf.nz;
    }
    const WindingNode& root = w.nodes()[0];
    EXPECT_EQ(root.count, n);
    EXPECT_NEAR(root.area, area, 1e-9 * area);
    EXPECT_NEAR(root.nx, nx, 1e-9 * area);
    EXPECT_NEAR(root.ny, ny, 1e-9 * area);
    EXPECT_NEAR(root.nz, nz, 1e-9 * area);
    const WindingView v = w.view();
    for (int i = 0; i < v.nodeCount; ++i) {
        const WindingNode& node = v.nodes[i];
        ASSERT_GE(node.count, 1);
        for (int t = node.first; t < node.first + node.count; ++t)
            for (int k = 0; k < 3; ++k) {
                const float* c = v.corners + 9 * static_cast<size_t>(t) + 3 * k;
                const Vec3 p(c[0], c[1], c[2]);
                ASSERT_LE(distance(p, node), node.radius * (1 + 1e-9) + 1e-9) << "node " << i;
                for (int a = 0; a < 3; ++a) {
                    ASSERT_GE(p[a], node.lo[a]);
                    ASSERT_LE(p[a], node.hi[a]);
                }
            }
    }
}

// Winding numbers from the LBVH's tree against the exact sum (first-order dipoles at beta = 3:
// the median-split tree's bound, 0.03) and inside() against the median-split tree's on a grid
// around each mesh; the tree stays within windingNumberFast's stack.
TEST(LbvhWinding, MatchesTheExactSumAndTheMedianTreesSigns) {
    for (const char* name : {"bunny_npm.obj", "elephant-with-holes.obj", "teapot.obj"}) {
        SCOPED_TRACE(name);
        const TriangleMesh mesh = load(name);
        const Lbvh lbvh(mesh);
        EXPECT_LT(lbvh.depth(), 100);
        const LbvhWinding tree(lbvh.view());
        const WindingNumber median(mesh);
        const Bounds3 b = mesh.bounds().expanded(0.1f * maxComponent(mesh.bounds().extent()));
        const int n = 24;
        int compared = 0, differ = 0, inside = 0;
        double worst = 0;
        for (int k = 0; k <= n; ++k)
            for (int j = 0; j <= n; ++j)
                for (int i = 0; i <= n; ++i) {
                    const Vec3 p = b.lo + b.extent() * Vec3(i, j, k) / static_cast<float>(n);
                    const bool in = windingInside(tree.view(), p, median.beta());
                    differ += in != median.inside(p);
                    inside += in;
                    if ((i + j + k) % 5 != 0) continue;  // the exact sum on a fifth of them
                    const double e = median.exact(p),
                                 f = windingNumberFast(tree.view(), p, median.beta());
                    worst = std::fmax(worst, std::fabs(e - f));
                    if (std::fabs(e - 0.5) > 0.05) {
                        EXPECT_EQ(e > 0.5, f > 0.5) << p.x << "," << p.y << "," << p.z;
                        ++compared;
                    }
                }
        std::printf(
            "[ winding ] %s: worst |fast - exact| %.4f; %d of %d signs differ from the "
            "median tree's\n",
            name, worst, differ, (n + 1) * (n + 1) * (n + 1));
        EXPECT_LT(worst, 0.03);
        EXPECT_GT(compared, 2000);
        EXPECT_GT(inside, 100);
        EXPECT_LE(differ, (n + 1) * (n + 1) * (n + 1) / 2000) << differ << " signs differ";
    }
}

}  // namespace
}  // namespace sdft
