// A mesh's or grid file's grid and its gap lattice (decision 19): derived when the render reads
// the grid's distance bound, left out when only the DDA walks it.
#include "sdftrace/scene/load_input.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "sdftrace/field/sample_grid.h"
#include "sdftrace/io/sdfg_io.h"

namespace sdft {
namespace {

TEST(LoadInput, OnlyRendersThatReadTheGridsDistancesNeedTheLattice) {
    RenderSettings s;  // the DDA, hard shadows
    EXPECT_FALSE(loneGridReadsDistances(s));
    s.shadows = false;
    EXPECT_FALSE(loneGridReadsDistances(s));
    s.shadows = true;
    s.shadowMethod = ShadowMethod::Distributed;  // the DDA's shadow rays
    EXPECT_FALSE(loneGridReadsDistances(s));
    for (ShadowMethod m : {ShadowMethod::Soft, ShadowMethod::Pcf, ShadowMethod::Evsm}) {
        s.shadowMethod = m;
        EXPECT_TRUE(loneGridReadsDistances(s));
        s.shadows = false;
        EXPECT_FALSE(loneGridReadsDistances(s));
        s.shadows = true;
    }
    s = {};
    s.ambientOcclusion = true;
    EXPECT_TRUE(loneGridReadsDistances(s));
    s = {};
    s.pathTracing = true;
    EXPECT_TRUE(loneGridReadsDistances(s));
    s = {};
    s.gridTracer = GridTracerKind::SphereTrace;
    EXPECT_TRUE(loneGridReadsDistances(s));
}

TEST(LoadInput, AGridFileGetsItsLatticeUnlessAsked) {
    const NodePtr sphere = node::sphere(1.0f);
    SampleOptions o;
    o.resolution = 48;
    const Grid g = sampleGrid(compileTape(sphere), nodeBounds(*sphere), o);
    const std::string path = ::testing::TempDir() + "sdftrace_load_input.sdfg";
    saveSdfg(g, path);
    for (bool lattice : {true, false}) {
        const LoadedInput in = loadSceneInput(path, false, {}, lattice);
        ASSERT_TRUE(in.scene.root && in.scene.root->grid);
        EXPECT_EQ(in.scene.root->grid->view().gapLattice != nullptr, lattice);
    }
    EXPECT_NE(loadSceneInput(path).scene.root->grid->view().gapLattice, nullptr);
    std::remove(path.c_str());
}

}  // namespace
}  // namespace sdft
