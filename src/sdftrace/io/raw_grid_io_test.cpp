#include "sdftrace/io/raw_grid_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <vector>

#include "sdftrace/core/error.h"
#include "sdftrace/field/sample_grid.h"
#include "test_files.h"

namespace sdft {
namespace {

using testing::tempPath;

TEST(RawGridIo, RoundTripsAndIsWhatNumpyReads) {
    const NodePtr box = node::box({0.4f, 0.3f, 0.2f});
    for (GridKind kind : {GridKind::Dense, GridKind::Sparse}) {
        SampleOptions o;
        o.resolution = 20;
        o.kind = kind;
        const Grid g = sampleGrid(compileTape(box, {.boundsCulling = false}), nodeBounds(*box), o);
        const std::string path = tempPath("box.raw");
        saveRawGrid(g, path);
        ASSERT_TRUE(std::filesystem::exists(rawSidecarPath(path)));
        // The file is the samples and nothing else, x fastest.
        const std::vector<float> samples = g.vertexSamples();
        ASSERT_EQ(std::filesystem::file_size(path), samples.size() * sizeof(float));
        const Grid back = loadRawGrid(path);
        EXPECT_EQ(back.vertexSamples(), samples);
        for (int a = 0; a < 3; ++a) EXPECT_EQ(back.shape().cells[a], g.shape().cells[a]);
        EXPECT_EQ(back.shape().origin.x, g.shape().origin.x);
        EXPECT_EQ(back.shape().voxelSize, g.shape().voxelSize);
        std::filesystem::remove(path);
        std::filesystem::remove(rawSidecarPath(path));
    }
}

TEST(RawGridIo, MissingOrInconsistentSidecarsFailClearly) {
    const std::string path = tempPath("bad.raw"), sidecar = rawSidecarPath(path);
    std::vector<float> eight(8, 1.0f);
    auto writeRaw = [&](const std::vector<float>& v) {
        std::ofstream(path, std::ios::binary)
            .write(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(float));
    };
    writeRaw(eight);
    std::filesystem::remove(sidecar);
    struct Case {
        const char* sidecar;  // nullptr: none
        const char* fragment;
    } cases[] = {
        {nullptr, "cannot open the sidecar"},
        {"{", "malformed JSON"},
        {R"({"format": "x", "dims": [2,2,2], "origin": [0,0,0], "voxel_size": 1})", "/format"},
        {R"({"format": "sdftrace-raw-float32", "dims": [2,2], "origin": [0,0,0], "voxel_size": 1})",
         "/dims: expected an array of three numbers"},
        {R"({"format": "sdftrace-raw-float32", "dims": [2,2,2.5], "origin": [0,0,0], "voxel_size": 1})",
         "/dims/2: expected an integer"},
        {R"({"format": "sdftrace-raw-float32", "dims": [2,2,3], "origin": [0,0,0], "voxel_size": 1})",
         "32 bytes, but the sidecar's dims 2x2x3 need 48"},
        {R"({"format": "sdftrace-raw-float32", "dims": [2,2,2], "origin": [0,0,0], "voxel_size": 0})",
         "the spacing must be a positive number"},
        {R"({"format": "sdftrace-raw-float32", "dims": [2,2,2], "origin": [0,0,0], "voxel_size": 1, "endian": "big"})",
         "/endian: unknown key"},
    };
    for (const Case& c : cases) {
        if (c.sidecar) std::ofstream(sidecar) << c.sidecar;
        try {
            loadRawGrid(path);
            ADD_FAILURE() << "accepted: " << (c.sidecar ? c.sidecar : "no sidecar");
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(c.fragment), std::string::npos) << e.what();
        }
    }
    // Non-finite samples.
    std::ofstream(sidecar)
        << R"({"format": "sdftrace-raw-float32", "dims": [2,2,2], "origin": [0,0,0], "voxel_size": 1})";
    eight[5] = NAN;
    writeRaw(eight);
    EXPECT_THROW(loadRawGrid(path), InputError);
    std::filesystem::remove(path);
    std::filesystem::remove(sidecar);
}

}  // namespace
}  // namespace sdft
