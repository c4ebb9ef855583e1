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

// OBJ as tools write it: groups, texture coordinates and normals, corners of every form, negative
// indices, quads, a face continued on the next line.
std::string obj(const TriangleMesh& m) {
    std::string s = "# written by a test\nmtllib cube.mtl\no cube\n";
    char line[160];
    for (const Vec3& p : m.positions) {
        std::snprintf(line, sizeof line, "v %.9g %.9g %.9g 1.0\n", p.x, p.y, p.z);
        s += line;
    }
    s += "vt 0 0\nvt 1 0\nvn 0 0 1\ng side\nusemtl grey\ns off\n";
    const char* forms[] = {"%u", "%u/1", "%u//1", "%u/2/1"};
    int k = 0;
    for (size_t f = 0; f + 1 < m.triangles.size(); f += 2, ++k) {  // the cube's quads
        const uint32_t q[4] = {m.triangles[f][0], m.triangles[f][1], m.triangles[f][2],
                               m.triangles[f + 1][2]};
        s += "f";
        for (int j = 0; j < 4; ++j) {
            // Face 1 by negative indices, face 2 continued after its second corner.
            const long index = k == 1
                                   ? static_cast<long>(q[j]) - static_cast<long>(m.positions.size())
                                   : static_cast<long>(q[j]) + 1;
            std::snprintf(line, sizeof line, forms[(j + k) % 4], static_cast<unsigned>(index));
            if (k == 1) std::snprintf(line, sizeof line, "%ld", index);
            s += " ";
            s += line;
            if (k == 2 && j == 1) s += " \\\n  ";
        }
        s += "\n";
    }
    return s + "l 1 2\np 3\n";
}

struct Variant {
    const char* name;
    std::string bytes;
};

std::vector<Variant> variants() {
    const TriangleMesh m = cube();
    return {{"ascii.ply", plyAscii(m)},
            {"little.ply", plyBinary(m, false)},
            {"big.ply", plyBinary(m, true)},
            {"binary.stl", stlBinary(m)},
            {"ascii.stl", stlAscii(m)},
            {"quads.off", off(m)},
            {"quads.obj", obj(m)}};
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
    EXPECT_EQ(ownMeshReader("x.gltf"), nullptr);
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

// OBJ's own errors: each one line with the file and line, what is wrong and what is accepted.
TEST(MeshReaders, ObjIndicesAreCheckedAgainstTheVerticesDefined) {
    TempDir dir;
    const std::string v = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    struct Case {
        std::string text, fragment;
    } cases[] = {
        {v + "f 1 2 0\n", ":4: OBJ: a face uses vertex 0 with 3 vertices read"},
        {v + "f 1 2 -4\n", ":4: OBJ: a face uses vertex -4"},
        {v + "f 1 2 4\n", ":4: OBJ: a face uses vertex 4, but the file defines 3 vertices"},
        {v + "f 1 2 x/1\n", ":4: OBJ: a face corner 'x/1'"},
        {"v 0 0\n", ":2: OBJ vertex: expected a number, found the end"},
        {"v 0 0 zero\n", ":1: OBJ vertex: expected a number, found 'zero'"},
        {"v 1e400 0 0\n", ":1: OBJ vertex: '1e400' is outside the range of double-precision"},
        {v + "f 1 2 99999999999999999999\n", "a face corner"},
    };
    for (const Case& c : cases) {
        const std::string path = dir.write("bad.obj", c.text);
        try {
            loadMesh(path);
            ADD_FAILURE() << "read: " << c.text;
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_EQ(what.rfind(path + ":", 0), 0u) << what;
            EXPECT_NE(what.find(c.fragment), std::string::npos) << what;
        }
    }
    // A face may name a vertex defined after it.
    const TriangleMesh m = loadMesh(dir.write("late.obj", "f 1 2 3\n" + v));
    EXPECT_EQ(m.triangles.size(), 1u);
}

// Concave polygons are cut inside themselves: the triangles cover the polygon's area exactly,
// all with its winding (a fan from a reflex corner would overlap and flip one).
TEST(MeshReaders, ConcavePolygonsTriangulateInsideThemselves) {
    TempDir dir;
    // An L, a dart (a concave quad) and a U in the plane z = 2, each starting at a corner from
    // which a fan leaves the polygon, in OBJ, OFF and ascii PLY.
    const std::vector<std::vector<std::array<float, 2>>> shapes = {
        {{1, 2}, {0, 2}, {0, 0}, {2, 0}, {2, 1}, {1, 1}},
        {{0, 0}, {2, 1}, {0, 2}, {1, 1}},
        {{1, 1}, {1, 3}, {0, 3}, {0, 0}, {3, 0}, {3, 3}, {2, 3}, {2, 1}},
    };
    for (size_t s = 0; s < shapes.size(); ++s) {
        const auto& shape = shapes[s];
        double area2 = 0;  // twice the signed area
        for (size_t j = 0; j < shape.size(); ++j) {
            const auto& a = shape[j];
            const auto& b = shape[(j + 1) % shape.size()];
            area2 += static_cast<double>(a[0]) * b[1] - static_cast<double>(b[0]) * a[1];
        }
        std::string objText,
            offText = "OFF\n" + std::to_string(shape.size()) + " 1 0\n",
            plyText = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(shape.size()) +
                      "\nproperty float x\nproperty float y\nproperty float "
                      "z\nelement face 1\nproperty list uchar int "
                      "vertex_indices\nend_header\n";
        std::string face = "f", offFace = std::to_string(shape.size()),
                    plyFace = std::to_string(shape.size());
        for (size_t j = 0; j < shape.size(); ++j) {
            const std::string xyz =
                std::to_string(shape[j][0]) + " " + std::to_string(shape[j][1]) + " 2\n";
            objText += "v " + xyz;
            offText += xyz;
            plyText += xyz;
            face += " " + std::to_string(j + 1);
            offFace += " " + std::to_string(j);
            plyFace += " " + std::to_string(j);
        }
        const std::pair<std::string, std::string> files[] = {
            {"shape.obj", objText + face + "\n"},
            {"shape.off", offText + offFace + "\n"},
            {"shape.ply", plyText + plyFace + "\n"}};
        for (const auto& [name, text] : files) {
            SCOPED_TRACE(name + " shape " + std::to_string(s));
            const MeshArrays a = ownMeshReader(name)(dir.write(name, text));
            ASSERT_EQ(a.triangles.size(), shape.size() - 2);
            double sum = 0;
            for (const auto& t : a.triangles) {
                const Vec3 n = cross(a.positions[t[1]] - a.positions[t[0]],
                                     a.positions[t[2]] - a.positions[t[0]]);
                EXPECT_GT(n.z * area2, 0) << "a triangle against the polygon's winding";
                sum += n.z;
            }
            EXPECT_NEAR(sum, area2, 1e-4);
        }
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
