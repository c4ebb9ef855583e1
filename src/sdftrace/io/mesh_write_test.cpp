#include "sdftrace/io/mesh_write.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "sdftrace/core/error.h"
#include "sdftrace/io/mesh_io.h"
#include "test_files.h"

namespace sdft {
namespace {

// A closed tetrahedron with coordinates that need every digit of a float.
TriangleMesh tetrahedron() {
    TriangleMesh m;
    m.positions = {{0.1f, -0.2f, 0.3f},
                   {1.0f / 3, 0.0f, 1e-7f},
                   {0.0f, 2.718281f, 0.0f},
                   {-1e5f, 3.14159265f, 1.5f}};
    m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    return m;
}

TEST(MeshWrite, EveryFormatReadsBackTheSameMesh) {
    const TriangleMesh m = tetrahedron();
    for (const char* ext : {".ply", ".obj", ".stl", ".PLY"}) {
        const std::string path = testing::tempPath(std::string("tet") + ext);
        saveMesh(m, path);
        MeshReport report;
        TriangleMesh back = loadMesh(path, &report);
        ASSERT_EQ(back.positions.size(), m.positions.size()) << ext;
        ASSERT_EQ(back.triangles.size(), m.triangles.size()) << ext;
        // Vertices may be renumbered (STL stores corners; the loader welds them): compare each
        // triangle's corner positions, exactly (binary floats and shortest round-trip text).
        for (size_t t = 0; t < m.triangles.size(); ++t)
            for (int c = 0; c < 3; ++c) {
                const Vec3 a = m.positions[m.triangles[t][c]];
                const Vec3 b = back.positions[back.triangles[t][c]];
                EXPECT_EQ(a.x, b.x) << ext;
                EXPECT_EQ(a.y, b.y) << ext;
                EXPECT_EQ(a.z, b.z) << ext;
            }
        std::filesystem::remove(path);
    }
}

TEST(MeshWrite, UnknownExtensionWritesNothing) {
    const std::string path = testing::tempPath("tet.off");
    EXPECT_FALSE(isMeshOutputFile(path));
    EXPECT_THROW(saveMesh(tetrahedron(), path), InputError);
    EXPECT_FALSE(std::filesystem::exists(path));
    EXPECT_THROW(saveMesh(tetrahedron(), "/nonexistent-dir/x.ply"), InputError);
}

}  // namespace
}  // namespace sdft
