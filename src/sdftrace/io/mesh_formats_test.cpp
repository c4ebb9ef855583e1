// The formats users bring (issue 17): the closed bunny written as PLY (ascii and binary), STL
// (ascii and binary), OFF, glTF (embedded buffer) and GLB, loaded back through assimp and cleaned:
// the same vertices, triangles and watertightness as from its OBJ.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "sdftrace/io/mesh_io.h"

namespace sdft {
namespace {

namespace fs = std::filesystem;

struct TempDir {
    fs::path path = fs::temp_directory_path() / ("sdft_formats_" + std::to_string(::getpid()));
    TempDir() { fs::create_directories(path); }
    ~TempDir() { fs::remove_all(path); }
    std::string file(const std::string& name) const { return (path / name).string(); }
};

template <class T>
void put(std::string& out, T v) {
    out.append(reinterpret_cast<const char*>(&v), sizeof v);
}

std::string plyHeader(const TriangleMesh& m, const char* format) {
    return std::string("ply\nformat ") + format + " 1.0\nelement vertex " +
           std::to_string(m.positions.size()) +
           "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
           std::to_string(m.triangles.size()) +
           "\nproperty list uchar int vertex_indices\nend_header\n";
}

// "x y z" lines, then "3 a b c" lines: the body of ascii PLY and of OFF.
std::string asciiVerticesAndFaces(const TriangleMesh& m) {
    std::string s;
    char line[128];
    for (const Vec3& p : m.positions) {
        std::snprintf(line, sizeof line, "%.9g %.9g %.9g\n", p.x, p.y, p.z);
        s += line;
    }
    for (const auto& t : m.triangles) {
        std::snprintf(line, sizeof line, "3 %u %u %u\n", t[0], t[1], t[2]);
        s += line;
    }
    return s;
}

std::string plyAscii(const TriangleMesh& m) {
    return plyHeader(m, "ascii") + asciiVerticesAndFaces(m);
}

std::string plyBinary(const TriangleMesh& m) {
    std::string s = plyHeader(m, "binary_little_endian");
    for (const Vec3& p : m.positions) put(s, p.x), put(s, p.y), put(s, p.z);
    for (const auto& t : m.triangles) {
        put(s, uint8_t{3});
        for (uint32_t v : t) put(s, static_cast<int32_t>(v));
    }
    return s;
}

Vec3 faceNormal(const TriangleMesh& m, const std::array<uint32_t, 3>& t) {
    return normalize(
        cross(m.positions[t[1]] - m.positions[t[0]], m.positions[t[2]] - m.positions[t[0]]));
}

std::string stlAscii(const TriangleMesh& m) {
    std::string s = "solid bunny\n";
    char line[160];
    for (const auto& t : m.triangles) {
        const Vec3 n = faceNormal(m, t);
        std::snprintf(line, sizeof line, "facet normal %.9g %.9g %.9g\nouter loop\n", n.x, n.y,
                      n.z);
        s += line;
        for (uint32_t v : t) {
            const Vec3 p = m.positions[v];
            std::snprintf(line, sizeof line, "vertex %.9g %.9g %.9g\n", p.x, p.y, p.z);
            s += line;
        }
        s += "endloop\nendfacet\n";
    }
    return s + "endsolid bunny\n";
}

std::string stlBinary(const TriangleMesh& m) {
    std::string s(80, ' ');
    put(s, static_cast<uint32_t>(m.triangles.size()));
    for (const auto& t : m.triangles) {
        const Vec3 n = faceNormal(m, t);
        put(s, n.x), put(s, n.y), put(s, n.z);
        for (uint32_t v : t)
            put(s, m.positions[v].x), put(s, m.positions[v].y), put(s, m.positions[v].z);
        put(s, uint16_t{0});
    }
    return s;
}

std::string off(const TriangleMesh& m) {
    return "OFF\n" + std::to_string(m.positions.size()) + " " + std::to_string(m.triangles.size()) +
           " 0\n" + asciiVerticesAndFaces(m);
}

std::string base64(const std::string& in) {
    static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < in.size(); i += 3) {
        uint32_t v = uint8_t(in[i]) << 16;
        if (i + 1 < in.size()) v |= uint8_t(in[i + 1]) << 8;
        if (i + 2 < in.size()) v |= uint8_t(in[i + 2]);
        out += k[(v >> 18) & 63];
        out += k[(v >> 12) & 63];
        out += i + 1 < in.size() ? k[(v >> 6) & 63] : '=';
        out += i + 2 < in.size() ? k[v & 63] : '=';
    }
    return out;
}

// glTF 2.0: one mesh, positions and uint32 indices in one buffer (embedded as a data URI, or
// the GLB binary chunk).
std::string gltf(const TriangleMesh& m, bool binary) {
    std::string buffer;
    Bounds3 b = m.bounds();
    for (const Vec3& p : m.positions) put(buffer, p.x), put(buffer, p.y), put(buffer, p.z);
    const size_t positionBytes = buffer.size();
    for (const auto& t : m.triangles)
        for (uint32_t v : t) put(buffer, v);
    char bounds[256];
    std::snprintf(bounds, sizeof bounds, "\"min\": [%.9g, %.9g, %.9g], \"max\": [%.9g, %.9g, %.9g]",
                  b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z);
    const std::string uri =
        binary ? "" : ", \"uri\": \"data:application/octet-stream;base64," + base64(buffer) + "\"";
    std::string json =
        R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
 "buffers": [{"byteLength": )" +
        std::to_string(buffer.size()) + uri + R"(}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": )" +
        std::to_string(positionBytes) + R"(},
                 {"buffer": 0, "byteOffset": )" +
        std::to_string(positionBytes) + R"(, "byteLength": )" +
        std::to_string(buffer.size() - positionBytes) + R"(}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": )" +
        std::to_string(m.positions.size()) + R"(, "type": "VEC3", )" + bounds + R"(},
               {"bufferView": 1, "componentType": 5125, "count": )" +
        std::to_string(3 * m.triangles.size()) + R"(, "type": "SCALAR"}]})";
    if (!binary) return json;
    while (json.size() % 4) json += ' ';
    while (buffer.size() % 4) buffer += '\0';
    std::string glb;
    put(glb, uint32_t{0x46546C67}), put(glb, uint32_t{2});
    put(glb, static_cast<uint32_t>(12 + 8 + json.size() + 8 + buffer.size()));
    put(glb, static_cast<uint32_t>(json.size())), put(glb, uint32_t{0x4E4F534A});
    glb += json;
    put(glb, static_cast<uint32_t>(buffer.size())), put(glb, uint32_t{0x004E4942});
    return glb + buffer;
}

TEST(MeshFormats, EveryFormatLoadsTheSameClosedMesh) {
    const TriangleMesh bunny =
        loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/bunny_npm.obj");
    ASSERT_TRUE(isWatertight(bunny));
    TempDir dir;
    const struct {
        const char* name;
        std::string bytes;
    } files[] = {
        {"bunny_ascii.ply", plyAscii(bunny)},
        {"bunny_binary.ply", plyBinary(bunny)},
        {"bunny_ascii.stl", stlAscii(bunny)},
        {"bunny_binary.stl", stlBinary(bunny)},
        {"bunny.off", off(bunny)},
        {"bunny.gltf", gltf(bunny, false)},
        {"bunny.glb", gltf(bunny, true)},
    };
    for (const auto& f : files) {
        std::ofstream(dir.file(f.name), std::ios::binary) << f.bytes;
        MeshReport r;
        TriangleMesh m;
        ASSERT_NO_THROW(m = loadMesh(dir.file(f.name), &r)) << f.name;
        EXPECT_EQ(m.positions.size(), bunny.positions.size()) << f.name;
        EXPECT_EQ(m.triangles.size(), bunny.triangles.size()) << f.name;
        EXPECT_TRUE(isWatertight(m)) << f.name;
        EXPECT_EQ(r.components, 1u) << f.name;
        const Bounds3 a = bunny.bounds(), b = m.bounds();
        EXPECT_LT(length(a.lo - b.lo) + length(a.hi - b.hi), 1e-5f) << f.name;
    }
}

}  // namespace
}  // namespace sdft
