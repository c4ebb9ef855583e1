#include "sdftrace/bake/extract_surface.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sdftrace/core/error.h"
#include "sdftrace/field/node.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/tape.h"

namespace sdft {
namespace {

Grid sampled(const NodePtr& root, int resolution, int blockSize = 8, float band = 3) {
    Tape tape = compileTape(root, {.boundsCulling = false});
    SampleOptions o;
    o.resolution = resolution;
    o.blockSize = blockSize;
    o.bandVoxels = band;
    return sampleGrid(tape, tape.bounds(), o);
}

// Six times the signed volume the triangles enclose (divergence theorem): > 0 when they wind
// counter-clockwise seen from outside.
double signedVolume(const TriangleMesh& m) {
    double v = 0;
    for (const auto& t : m.triangles) {
        const Vec3 a = m.positions[t[0]], b = m.positions[t[1]], c = m.positions[t[2]];
        v += dot(a, cross(b, c));
    }
    return v / 6;
}

TEST(ExtractSurface, SphereIsClosedOutwardAndOnTheSurface) {
    for (int block : {4, 8}) {
        Grid g = sampled(node::sphere(1), 64, block);
        const float h = g.shape().voxelSize;
        TriangleMesh m = extractSurface(g, {}, "sphere");
        ASSERT_GT(m.triangles.size(), 1000u);
        EXPECT_TRUE(isWatertight(m));
        float worst = 0;
        for (const Vec3& p : m.positions) worst = std::max(worst, std::fabs(length(p) - 1));
        // Vertices sit on the trilinear reconstruction's zero set, within a small part of a voxel
        // of the exact sphere.
        EXPECT_LT(worst, 0.1f * h) << "block " << block;
        const double exact = 4.0 / 3.0 * M_PI;
        EXPECT_NEAR(signedVolume(m), exact, 0.01 * exact) << "block " << block;
        // Every triangle faces away from the centre.
        size_t inward = 0;
        for (const auto& t : m.triangles) {
            const Vec3 a = m.positions[t[0]], b = m.positions[t[1]], c = m.positions[t[2]];
            if (dot(cross(b - a, c - a), a + b + c) <= 0) ++inward;
        }
        EXPECT_EQ(inward, 0u);
    }
}

TEST(ExtractSurface, IsovalueGivesTheOffsetSurface) {
    Grid g = sampled(node::sphere(1), 64, 8, 6);
    TriangleMesh m = extractSurface(g, {.isovalue = 0.1f}, "sphere");
    for (const Vec3& p : m.positions) EXPECT_NEAR(length(p), 1.1f, 0.01f);
    TriangleMesh inner = extractSurface(g, {.isovalue = -0.1f}, "sphere");
    for (const Vec3& p : inner.positions) EXPECT_NEAR(length(p), 0.9f, 0.01f);
}

TEST(ExtractSurface, AdaptivityMergesFlatRegions) {
    Grid g = sampled(node::box({1.0f, 0.6f, 0.4f}), 64);
    const float h = g.shape().voxelSize;
    TriangleMesh full = extractSurface(g, {}, "box");
    TriangleMesh merged = extractSurface(g, {.adaptivity = 0.9f}, "box");
    EXPECT_LT(merged.triangles.size() * 4, full.triangles.size());
    for (const TriangleMesh* m : {&full, &merged}) {
        EXPECT_TRUE(isWatertight(*m));
        // Vertices on the box's surface: within a voxel (the trilinear reconstruction rounds the
        // edges and corners), a quarter of one on average.
        double sum = 0;
        float worst = 0;
        for (const Vec3& p : m->positions) {
            const Vec3 q = abs(p) - Vec3(1.0f, 0.6f, 0.4f);
            const float d = std::fabs(length(max(q, Vec3(0.0f))) + std::min(maxComponent(q), 0.0f));
            sum += d;
            worst = std::max(worst, d);
        }
        EXPECT_LT(worst, h);
        EXPECT_LT(sum / m->positions.size(), 0.25 * h);
    }
    const double exact = 8.0 * 1.0 * 0.6 * 0.4;
    EXPECT_NEAR(signedVolume(merged), exact, 0.02 * exact);
}

TEST(ExtractSurface, RefusesWhatIsNotThere) {
    Grid g = sampled(node::sphere(1), 32);
    // Beyond the stored band the samples are clamped: no offset surface there.
    EXPECT_THROW(extractSurface(g, {.isovalue = 0.5f}, "sphere"), InputError);
    EXPECT_THROW(extractSurface(g, {.isovalue = NAN}, "sphere"), InputError);
    EXPECT_THROW(extractSurface(g, {.adaptivity = 1.5f}, "sphere"), InputError);
    // A grid without a sign change has no surface.
    GridShape s;
    s.cells[0] = s.cells[1] = s.cells[2] = 8;
    s.voxelSize = 0.1f;
    Grid empty = Grid::dense(s, std::vector<float>(s.vertexCount(), 0.05f));
    try {
        extractSurface(empty, {}, "empty.sdfg");
        FAIL() << "no exception";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("empty.sdfg: no surface"), std::string::npos)
            << e.what();
    }
}

}  // namespace
}  // namespace sdft
