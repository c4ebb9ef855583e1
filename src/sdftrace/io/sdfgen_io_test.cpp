#include "sdftrace/io/sdfgen_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/field/sample_grid.h"
#include "test_files.h"

namespace sdft {
namespace {

using testing::tempPath;

Grid torusGrid(GridKind kind) {
    const NodePtr torus = node::torus(0.7f, 0.2f);
    SampleOptions o;
    o.resolution = 24;
    o.kind = kind;
    return sampleGrid(compileTape(torus, {.boundsCulling = false}), nodeBounds(*torus), o);
}

void expectSameVertices(const Grid& a, const Grid& b) {
    ASSERT_EQ(a.shape().vertexCount(), b.shape().vertexCount());
    for (int axis = 0; axis < 3; ++axis) {
        EXPECT_EQ(a.shape().cells[axis], b.shape().cells[axis]);
        EXPECT_EQ(a.shape().origin[axis], b.shape().origin[axis]);
    }
    EXPECT_EQ(a.shape().voxelSize, b.shape().voxelSize);
    EXPECT_EQ(a.vertexSamples(), b.vertexSamples()) << "every sample round-trips exactly";
}

TEST(SdfgenIo, DenseAndSparseGridsRoundTripExactly) {
    for (GridKind kind : {GridKind::Dense, GridKind::Sparse}) {
        const Grid g = torusGrid(kind);
        const std::string path = tempPath("torus.sdf");
        saveSdfgen(g, path);
        const Grid back = loadSdfgen(path);
        EXPECT_EQ(back.kind(), GridKind::Dense);
        expectSameVertices(g, back);
        std::filesystem::remove(path);
    }
}

// A file as SDFGen itself writes it (ostream's default 6 digits, one value per line).
TEST(SdfgenIo, ReadsSdfgenOutput) {
    const std::string path = tempPath("sdfgen.sdf");
    std::ofstream(path) << "3 2 2\n-0.5 -0.25 0\n0.25\n"
                        << "0.1\n0.2\n0.3\n-0.1\n-0.2\n-0.3\n1\n2\n3\n4\n5\n6.5e-07\n";
    const Grid g = loadSdfgen(path);
    EXPECT_EQ(g.shape().cells[0], 2);
    EXPECT_EQ(g.shape().cells[1], 1);
    EXPECT_EQ(g.shape().cells[2], 1);
    EXPECT_FLOAT_EQ(g.shape().origin.y, -0.25f);
    EXPECT_FLOAT_EQ(g.shape().voxelSize, 0.25f);
    const GridView v = g.view();
    EXPECT_FLOAT_EQ(v.vertex(2, 0, 0), 0.3f);   // i fastest
    EXPECT_FLOAT_EQ(v.vertex(0, 1, 0), -0.1f);  // then j
    EXPECT_FLOAT_EQ(v.vertex(1, 0, 1), 2.0f);   // then k
    EXPECT_FLOAT_EQ(v.vertex(2, 1, 1), 6.5e-7f);
    std::filesystem::remove(path);
}

TEST(SdfgenIo, MalformedFilesFailWithTheLine) {
    struct Case {
        const char* text;
        const char* fragment;
    } cases[] = {
        {"2 2 2\n0 0 0\n1\n1 2 3 4 5 6 7      \n", "line 5: the file ends before a distance value"},
        // Held to the file's length before anything is allocated.
        {"2 2 2\n0 0 0\n1\n1 2 3 4 5 6\n", "the file ends before its 8 values"},
        {"300 300 300\n0 0 0\n1\n1 2\n", "the file ends before its 27000000 values"},
        {"2 2 2\n0 0 0\n1\n1 2 3 4 5 6 7 8 9\n", "more values than ni*nj*nk = 8"},
        {"2 2 2\n0 0 0\n1\n1 2 3 x 5 6 7 8\n", "line 4: expected a distance value, found 'x'"},
        {"2 2 2\n0 0 0\n1\n1 2 3 nan 5 6 7 8\n", "non-finite distance value"},
        {"1 2 2\n0 0 0\n1\n1 2 3 4\n", "1x2x2 samples is out of range"},
        {"2 2 2\n0 0 0\n-1\n1 2 3 4 5 6 7 8\n", "the spacing must be a positive number"},
        {"2 2 2\n0 inf 0\n1\n1 2 3 4 5 6 7 8\n", "origin must be finite"},
        {"2.5 2 2\n", "expected a sample count"},
        {"", "the file ends before a sample count"},
        {"30000 30000 30000\n0 0 0\n1\n", "more than the memory budget"},
    };
    const std::string path = tempPath("bad.sdf");
    for (const Case& c : cases) {
        std::ofstream(path) << c.text;
        try {
            loadSdfgen(path);
            ADD_FAILURE() << "accepted: " << c.text;
        } catch (const InputError& e) {
            const std::string m = e.what();
            EXPECT_NE(m.find(path), std::string::npos) << m;
            EXPECT_NE(m.find(c.fragment), std::string::npos) << m;
        }
    }
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace sdft
