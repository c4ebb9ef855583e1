// OFF (Geomview's Object File Format): "OFF" (or COFF, NOFF, CNOFF: per-vertex colours or
// normals after the position), the vertex, face and edge counts, then a vertex per line and a
// face per line ("k i0 ... ik-1", then an optional colour). '#' starts a comment. Counts are held
// to the file's bytes before anything is read (a vertex line takes at least 6 bytes, a face 8).
#include <string_view>

#include "polygon_triangulation.h"
#include "sdftrace/io/mapped_file.h"
#include "sdftrace/io/mesh_readers.h"
#include "sdftrace/io/text_cursor.h"

namespace sdft {

MeshArrays readOff(const std::string& path) {
    const MappedFile file(path);
    TextCursor c(file.data(), file.data() + file.size(), path);
    c.allowComments(true);
    const std::string_view magic = c.token();
    if (magic != "OFF" && magic != "COFF" && magic != "NOFF" && magic != "CNOFF")
        c.fail("OFF: the file does not start with 'OFF' (accepted: OFF, COFF, NOFF, CNOFF)");
    const int64_t nv = c.integer("OFF vertex count"), nf = c.integer("OFF face count");
    c.integer("OFF edge count");
    const double left = static_cast<double>(file.data() + file.size() - c.position());
    if (nv < 0 || nf < 0 || nv > UINT32_MAX ||
        6.0 * static_cast<double>(nv) + 8.0 * static_cast<double>(nf) > left + 2)
        c.fail("OFF: declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
               " faces, more than the " + std::to_string(static_cast<uint64_t>(left)) +
               " bytes that follow can hold (is the file cut short?)");
    MeshArrays out;
    out.positions.reserve(static_cast<size_t>(nv));
    for (int64_t v = 0; v < nv; ++v) {
        Vec3 p;
        for (int a = 0; a < 3; ++a) p[a] = toFloatCoordinate(c.number("OFF vertex"));
        out.positions.push_back(p);
        while (c.moreOnLine()) c.token();  // colour or normal
    }
    std::vector<uint32_t> poly;
    for (int64_t f = 0; f < nf; ++f) {
        const int64_t k = c.integer("OFF face's vertex count");
        if (k < 0 || k > 1000000) c.fail("OFF: a face of " + std::to_string(k) + " vertices");
        poly.clear();
        for (int64_t j = 0; j < k; ++j) {
            const int64_t i = c.integer("OFF face's vertex index");
            if (i < 0 || i >= nv)
                c.fail("OFF: face " + std::to_string(f) + " uses vertex " + std::to_string(i) +
                       ", but there are " + std::to_string(nv) +
                       " vertices (accepted: indices below the vertex count)");
            poly.push_back(static_cast<uint32_t>(i));
        }
        while (c.moreOnLine()) c.token();  // a colour
        triangulatePolygon(out.positions, poly, out.triangles);
    }
    return out;
}

}  // namespace sdft
