#include "sdftrace/bake/verify_bake.h"

#include <gtest/gtest.h>

#include "sdftrace/field/sample_grid.h"

namespace sdft {
namespace {

// A grid sampled from a field matches it at the vertices; between them the trilinear
// reconstruction of a sphere of radius R errs by at most about 3 h^2 / (8 R) (each axis'
// interpolation of a function of curvature 1 / R), and an offset field shows as its offset.
TEST(VerifyBake, AgainstTheFieldItWasSampledFrom) {
    const float R = 1.0f;
    const NodePtr sphere = node::sphere(R);
    const Tape tape = compileTape(sphere, {.boundsCulling = false});
    SampleOptions o;
    o.resolution = 32;
    o.kind = GridKind::Dense;
    const Grid g = sampleGrid(tape, nodeBounds(*sphere), o);
    const float h = g.shape().voxelSize;
    const FieldVerification v = verifyAgainstField(g, tape, 3.0f, 1);
    EXPECT_EQ(v.vertices.all.max, 0.0);
    EXPECT_GT(v.centres.count, 1000u);
    EXPECT_GT(v.centres.max, 0.0) << "the reconstruction is not exact between samples";
    EXPECT_LE(v.centres.max * h, 3.0 * h * h / (8.0 * (R - 3 * h)));
    EXPECT_EQ(v.wrongSignCentres, 0u);
    // The same samples shifted by a third of a voxel: found at every vertex near the surface.
    std::vector<float> shifted = g.vertexSamples();
    for (float& s : shifted) s += h / 3;
    const FieldVerification off =
        verifyAgainstField(Grid::dense(g.shape(), shifted), tape, 3.0f, 1);
    EXPECT_NEAR(off.vertices.band.max, 1.0 / 3, 1e-3);
    EXPECT_GT(off.vertices.wrongSigns, 0u);
}

}  // namespace
}  // namespace sdft
