// STL (3D Systems): binary, an 80-byte header, a triangle count and 50 bytes per triangle; or
// ascii, "solid ... facet normal ... outer loop / vertex x y z ... endloop endfacet ... endsolid".
// A binary file is recognised by its size (84 + 50 × its count), whatever its header says (many
// binary files start with "solid"); a file that neither fits its count nor reads as ascii STL is
// refused with both sizes named.
#include <algorithm>
#include <cstring>
#include <string_view>

#include "sdftrace/io/mapped_file.h"
#include "sdftrace/io/mesh_readers.h"
#include "sdftrace/io/text_cursor.h"

namespace sdft {

namespace {

MeshArrays binaryStl(const char* data, uint64_t count) {
    MeshArrays out;
    out.positions.reserve(3 * count);
    out.triangles.reserve(count);
    const char* p = data + 84;
    for (uint64_t t = 0; t < count; ++t, p += 50) {
        float v[9];
        std::memcpy(v, p + 12, sizeof v);  // after the facet normal
        const auto base = static_cast<uint32_t>(out.positions.size());
        for (int k = 0; k < 3; ++k) out.positions.push_back({v[3 * k], v[3 * k + 1], v[3 * k + 2]});
        out.triangles.push_back({base, base + 1, base + 2});
    }
    return out;
}

MeshArrays asciiStl(const char* begin, const char* end, const std::string& path) {
    TextCursor c(begin, end, path);
    MeshArrays out;
    if (c.token() != "solid") c.fail("STL: neither binary (its size) nor ascii ('solid')");
    c.skipLine();  // the solid's name
    std::vector<uint32_t> loop;
    bool inLoop = false;
    for (;;) {
        const std::string_view t = c.token();
        if (t.empty()) break;  // a missing "endsolid" is forgiven
        if (t == "vertex") {
            if (!inLoop) c.fail("STL: 'vertex' outside 'outer loop'");
            Vec3 p;
            for (int a = 0; a < 3; ++a) p[a] = toFloatCoordinate(c.number("STL vertex"));
            loop.push_back(static_cast<uint32_t>(out.positions.size()));
            out.positions.push_back(p);
        } else if (t == "outer") {
            if (c.token() != "loop") c.fail("STL: expected 'outer loop'");
            inLoop = true;
            loop.clear();
        } else if (t == "endloop") {
            if (!inLoop) c.fail("STL: 'endloop' without 'outer loop'");
            inLoop = false;
            for (size_t j = 2; j < loop.size(); ++j)
                out.triangles.push_back({loop[0], loop[j - 1], loop[j]});
        } else if (t == "facet") {
            if (inLoop) c.fail("STL: 'facet' inside a loop (a missing 'endloop')");
            c.skipLine();  // "normal nx ny nz": recomputed from the vertices
        } else if (t == "endfacet") {
        } else if (t == "endsolid") {
            c.skipLine();
            if (c.token() != "solid") break;  // several solids in one file
            c.skipLine();
        } else {
            c.fail("STL: unexpected '" + TextCursor::printable(t.substr(0, 32)) +
                   "'; accepted: facet, outer loop, vertex, endloop, endfacet, endsolid");
        }
    }
    if (inLoop) c.fail("STL: the file ends inside a loop (is it cut short?)");
    return out;
}

}  // namespace

MeshArrays readStl(const std::string& path) {
    const MappedFile file(path);
    const char* data = file.data();
    const size_t size = file.size();
    uint32_t count = 0;
    if (size >= 84) std::memcpy(&count, data + 80, 4);
    if (size >= 84 && 84 + 50 * static_cast<uint64_t>(count) == size) return binaryStl(data, count);
    size_t i = 0;
    while (i < size && (data[i] == ' ' || data[i] == '\t' || data[i] == '\r' || data[i] == '\n'))
        ++i;
    // A binary file's header may start with "solid" too: one with NUL bytes near its start whose
    // count does not fit is reported as binary.
    const bool text = size == 0 || std::memchr(data, 0, std::min<size_t>(size, 512)) == nullptr;
    if (size - i >= 5 && std::memcmp(data + i, "solid", 5) == 0 && (text || size < 84))
        return asciiStl(data, data + size, path);
    if (size < 84)
        throw InputError(path + ": STL: " + std::to_string(size) +
                         " bytes, shorter than a binary STL's 84-byte header, and not ascii STL "
                         "('solid ...')");
    throw InputError(path + ": STL: binary STL declares " + std::to_string(count) + " triangles, " +
                     std::to_string(84 + 50 * static_cast<uint64_t>(count)) +
                     " bytes, but the file has " + std::to_string(size) +
                     " (is it cut short or damaged?)");
}

}  // namespace sdft
