// sdftrace's own PLY, STL and OFF readers (mesh_readers.h): a mesh written in every variant reads
// back as the same cleaned mesh; files cut short at every length and with bytes changed at random
// end in one InputError naming the file, never a crash, a hang or an allocation their size does
// not justify.
#include "sdftrace/io/mesh_readers.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "sdftrace/core/error.h"
#include "sdftrace/io/mesh_io.h"

namespace sdft {
namespace {

namespace fs = std::filesystem;

struct TempDir {
    fs::path path = fs::temp_directory_path() / ("sdft_readers_" + std::to_string(::getpid()));
    TempDir() { fs::create_directories(path); }
    ~TempDir() { fs::remove_all(path); }
    std::string write(const std::string& name, const std::string& bytes) const {
        const std::string f = (path / name).string();
        std::ofstream(f, std::ios::binary) << bytes;
        return f;
    }
};

template <class T>
void put(std::string& out, T v, bool big = false) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof v);
    if (big) std::reverse(b, b + sizeof b);
    out.append(b, sizeof b);
}

// A small closed mesh with quads (an octahedron's top as quads would not close; a cube does).
TriangleMesh cube() {
    TriangleMesh m;
    for (int i = 0; i < 8; ++i)
        m.positions.push_back({i & 1 ? 1.f : -1.f, i & 2 ? 1.f : -1.f, i & 4 ? 1.f : -1.f});
    const uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                              {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : q) {
        m.triangles.push_back({f[0], f[1], f[2]});
        m.triangles.push_back({f[0], f[2], f[3]});
    }
    return m;
}

std::string plyHeader(const TriangleMesh& m, const char* format, const char* vertexType,
                      const char* listTypes) {
    return std::string("ply\nformat ") + format +
           " 1.0\ncomment written by a test\nelement vertex " + std::to_string(m.positions.size()) +
           "\nproperty " + vertexType + " x\nproperty " + vertexType + " y\nproperty " +
           vertexType + " z\nproperty uchar red\nelement face " +
           std::to_string(m.triangles.size()) + "\nproperty list " + listTypes +
           " vertex_indices\nproperty float quality\nend_header\n";
}

std::string plyAscii(const TriangleMesh& m) {
    std::string s = plyHeader(m, "ascii", "float", "uchar int");
    char line[128];
    for (const Vec3& p : m.positions) {
        std::snprintf(line, sizeof line, "%.9g %.9g %.9g 7\n", p.x, p.y, p.z);
        s += line;
    }
    for (const auto& t : m.triangles) {
        std::snprintf(line, sizeof line, "3 %u %u %u 0.5\n", t[0], t[1], t[2]);
        s += line;
    }
    return s;
}

std::string plyBinary(const TriangleMesh& m, bool big) {
    std::string s =
        plyHeader(m, big ? "binary_big_endian" : "binary_little_endian", "double", "uchar uint");
    for (const Vec3& p : m.positions) {
        for (int a = 0; a < 3; ++a) put<double>(s, p[a], big);
        put<uint8_t>(s, 7);
    }
    for (const auto& t : m.triangles) {
        put<uint8_t>(s, 3);
        for (uint32_t i : t) put<uint32_t>(s, i, big);
        put<float>(s, 0.5f, big);
    }
    return s;
}

std::string stlBinary(const TriangleMesh& m) {
    std::string s = "solid but binary";  // many binary files start so
    s.resize(80, ' ');
    put<uint32_t>(s, static_cast<uint32_t>(m.triangles.size()));
    for (const auto& t : m.triangles) {
        for (int k = 0; k < 3; ++k) put<float>(s, 0.0f);
        for (uint32_t i : t)
            for (int a = 0; a < 3; ++a) put<float>(s, m.positions[i][a]);
        put<uint16_t>(s, 0);
    }
    return s;
}

std::string stlAscii(const TriangleMesh& m) {
    std::string s = "solid cube\n";
    char line[160];
    for (const auto& t : m.triangles) {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for (uint32_t i : t) {
            const Vec3 p = m.positions[i];
            std::snprintf(line, sizeof line, "      vertex %.9g %.9g %.9g\n", p.x, p.y, p.z);
            s += line;
        }
        s += "    endloop\n  endfacet\n";
    }
    return s + "endsolid cube\n";
}

std::string off(const TriangleMesh& m) {
    std::string s = "OFF\n# a comment\n" + std::to_string(m.positions.size()) + " " +
                    std::to_string(m.triangles.size() / 2) + " 0\n";
    char line[128];
    for (const Vec3& p : m.positions) {
        std::snprintf(line, sizeof line, "%.9g %.9g %.9g\n", p.x, p.y, p.z);
        s += line;
    }
    for (size_t f = 0; f + 1 < m.triangles.size(); f += 2) {  // the cube's quads
        const auto& a = m.triangles[f];
        const auto& b = m.triangles[f + 1];
        std::snprintf(line, sizeof line, "4 %u %u %u %u 255 0 0\n", a[0], a[1], a[2], b[2]);
        s += line;
    }
    return s;
}

struct Variant {
    const char* name;
    std::string bytes;
};

std::vector<Variant> variants() {
    const TriangleMesh m = cube();
    return {{"ascii.ply", plyAscii(m)},      {"little.ply", plyBinary(m, false)},
            {"big.ply", plyBinary(m, true)}, {"binary.stl", stlBinary(m)},
            {"ascii.stl", stlAscii(m)},      {"quads.off", off(m)}};
}

TEST(MeshReaders, EveryVariantReadsTheSameMesh) {
    TempDir dir;
    const TriangleMesh m = cube();
    for (const Variant& v : variants()) {
        SCOPED_TRACE(v.name);
        const std::string path = dir.write(v.name, v.bytes);
        ASSERT_NE(ownMeshReader(path), nullptr);
        MeshReport report;
        const TriangleMesh read = loadMesh(path, &report);
        EXPECT_EQ(read.positions.size(), 8u);
        EXPECT_EQ(read.triangles.size(), 12u);
        EXPECT_EQ(report.boundaryEdges, 0u) << report.summary();
        EXPECT_EQ(report.components, 1u);
        EXPECT_EQ(report.degenerateTriangles, 0u);
    }
    EXPECT_EQ(ownMeshReader("x.obj"), nullptr);
    EXPECT_NE(ownMeshReader("X.PLY"), nullptr);
}

// The file of the report: a binary PLY whose header promises 1,000 vertices and 2,000 faces and
// whose body stops after three vertices (assimp crashed on it).
TEST(MeshReaders, APlyCutShortIsOneLine) {
    TempDir dir;
    std::string s =
        "ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\n"
        "property float y\nproperty float z\nelement face 2000\n"
        "property list uchar int vertex_indices\nend_header\n";
    for (float f : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) put<float>(s, f);
    const std::string path = dir.write("cut.ply", s);
    try {
        loadMesh(path);
        FAIL() << "read";
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_EQ(what.rfind(path + ": PLY: ", 0), 0u) << what;
        EXPECT_NE(what.find("1000 vertex and 2000 face records"), std::string::npos) << what;
    }
}

// Every variant cut short at every length, and with single bytes changed at random: each load
// ends with the mesh or one InputError naming the file.
TEST(MeshReaders, DamagedFilesEndInOneError) {
    TempDir dir;
    std::mt19937 rng(7);
    int errors = 0, loaded = 0;
    for (const Variant& v : variants()) {
        SCOPED_TRACE(v.name);
        auto attempt = [&](const std::string& bytes) {
            const std::string path = dir.write(v.name, bytes);
            try {
                loadMesh(path);
                ++loaded;
            } catch (const InputError& e) {
                ++errors;
                const std::string what = e.what();
                EXPECT_EQ(what.rfind(path, 0), 0u) << what;
                EXPECT_EQ(what.find('\n'), std::string::npos) << what;
            }
        };
        for (size_t n = 0; n < v.bytes.size(); n += 1 + v.bytes.size() / 300)
            attempt(v.bytes.substr(0, n));
        for (int k = 0; k < 300; ++k) {
            std::string b = v.bytes;
            const int changes = 1 + static_cast<int>(rng() % 4);
            for (int c = 0; c < changes; ++c) b[rng() % b.size()] = static_cast<char>(rng());
            attempt(b);
        }
    }
    EXPECT_GT(errors, 500);
    EXPECT_GT(loaded, 50);
}

}  // namespace
}  // namespace sdft
