#include "sdftrace/io/mesh_write.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cstring>
#include <filesystem>

#include "sdftrace/core/error.h"
#include "sdftrace/io/atomic_file.h"

namespace sdft {

namespace {

static_assert(std::endian::native == std::endian::little, "binary PLY and STL are little-endian");

std::string extensionOf(const std::string& path) {
    std::string e = std::filesystem::path(path).extension().string();
    std::transform(e.begin(), e.end(), e.begin(), ::tolower);
    return e;
}

// Bytes gathered in a buffer and handed to the output in large writes.
class Writer {
  public:
    explicit Writer(AtomicOutput& out) : m_out(out) { m_buf.reserve(kChunk + 256); }
    void bytes(const void* p, size_t n) {
        m_buf.append(static_cast<const char*>(p), n);
        if (m_buf.size() >= kChunk) flush();
    }
    void text(const char* s) { bytes(s, std::strlen(s)); }
    template <class T>
    void value(T v) {
        bytes(&v, sizeof v);
    }
    template <class T>
    void number(T v) {
        char tmp[32];
        auto r = std::to_chars(tmp, tmp + sizeof tmp, v);
        bytes(tmp, static_cast<size_t>(r.ptr - tmp));
    }
    void flush() {
        if (!m_buf.empty()) m_out.write(m_buf.data(), m_buf.size());
        m_buf.clear();
    }

  private:
    static constexpr size_t kChunk = 1 << 20;
    AtomicOutput& m_out;
    std::string m_buf;
};

void writePly(const TriangleMesh& m, Writer& w) {
    const std::string header =
        "ply\nformat binary_little_endian 1.0\ncomment sdftrace mesh\nelement vertex " +
        std::to_string(m.positions.size()) +
        "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
        std::to_string(m.triangles.size()) +
        "\nproperty list uchar uint vertex_indices\nend_header\n";
    w.bytes(header.data(), header.size());
    for (const Vec3& p : m.positions) {
        const float xyz[3] = {p.x, p.y, p.z};
        w.bytes(xyz, sizeof xyz);
    }
    for (const auto& t : m.triangles) {
        w.value<uint8_t>(3);
        w.bytes(t.data(), 3 * sizeof(uint32_t));
    }
}

void writeObj(const TriangleMesh& m, Writer& w) {
    w.text("# sdftrace mesh\n");
    for (const Vec3& p : m.positions) {
        w.text("v ");
        w.number(p.x);
        w.text(" ");
        w.number(p.y);
        w.text(" ");
        w.number(p.z);
        w.text("\n");
    }
    for (const auto& t : m.triangles) {
        w.text("f ");
        w.number(t[0] + 1);
        w.text(" ");
        w.number(t[1] + 1);
        w.text(" ");
        w.number(t[2] + 1);
        w.text("\n");
    }
}

void writeStl(const TriangleMesh& m, Writer& w) {
    char header[80] = {};
    std::snprintf(header, sizeof header, "sdftrace mesh");
    w.bytes(header, sizeof header);
    w.value<uint32_t>(static_cast<uint32_t>(m.triangles.size()));
    for (const auto& t : m.triangles) {
        const Vec3 a = m.positions[t[0]], b = m.positions[t[1]], c = m.positions[t[2]];
        Vec3 n = cross(b - a, c - a);
        const float len = length(n);
        n = len > 0 ? n / len : Vec3(0, 0, 0);
        const float rec[12] = {n.x, n.y, n.z, a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z};
        w.bytes(rec, sizeof rec);
        w.value<uint16_t>(0);
    }
}

}  // namespace

bool isMeshOutputFile(const std::string& path) {
    const std::string e = extensionOf(path);
    return e == ".ply" || e == ".obj" || e == ".stl";
}

void saveMesh(const TriangleMesh& mesh, const std::string& path) {
    const std::string e = extensionOf(path);
    if (!isMeshOutputFile(path))
        throw InputError(path + ": accepted mesh extensions: .ply (binary), .obj, .stl (binary)");
    if (e == ".stl" && mesh.triangles.size() > 0xffffffffu)
        throw InputError(path + ": binary STL holds at most 2^32 - 1 triangles; write .ply");
    AtomicOutput out(path);
    Writer w(out);
    if (e == ".ply")
        writePly(mesh, w);
    else if (e == ".obj")
        writeObj(mesh, w);
    else
        writeStl(mesh, w);
    w.flush();
    out.commit();
}

}  // namespace sdft
