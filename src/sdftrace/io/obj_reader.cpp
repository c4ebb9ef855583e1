// Wavefront OBJ: 'v x y z' vertices (a w or a colour after them ignored) and 'f' faces whose
// corners are 'i', 'i/t', 'i//n' or 'i/t/n', indices from 1 or, negative, counted back from the
// last vertex read; polygons triangulated in their plane (polygon_triangulation.h), a '\' at the
// end of a face's line continues it. Everything else (texture coordinates, normals, groups,
// materials, smoothing, lines, points, free-form curves) is skipped; '#' starts a comment. A
// vertex line takes at least 7 bytes and a face corner 2, so what the file holds bounds what is
// allocated; every index is checked against the vertices the file defines.
#include <string_view>

#include "polygon_triangulation.h"
#include "sdftrace/io/mapped_file.h"
#include "sdftrace/io/mesh_readers.h"
#include "sdftrace/io/text_cursor.h"

namespace sdft {

namespace {

// A face corner's vertex index (the part before the first '/').
int64_t cornerIndex(std::string_view corner, TextCursor& c) {
    int64_t v = 0;
    if (!TextCursor::toInteger(corner.substr(0, corner.find('/')), v))
        c.fail("OBJ: a face corner '" + TextCursor::printable(corner.substr(0, 32)) +
               "' (accepted: i, i/t, i//n, i/t/n with integer indices)");
    return v;
}

}  // namespace

MeshArrays readObj(const std::string& path) {
    const MappedFile file(path);
    TextCursor c(file.data(), file.data() + file.size(), path);
    c.allowComments(true);
    MeshArrays out;
    // Faces as read (0-based where known; a positive index may name a vertex defined later).
    std::vector<uint32_t> corners;
    std::vector<size_t> faceStart;
    int64_t largest = -1;
    int largestLine = 0;
    while (!c.atEnd()) {
        const std::string_view key = c.token();
        if (key == "v") {
            Vec3 p;
            for (int a = 0; a < 3; ++a) p[a] = toFloatCoordinate(c.number("OBJ vertex"));
            if (out.positions.size() >= UINT32_MAX) c.fail("OBJ: more than 2^32 - 1 vertices");
            out.positions.push_back(p);
            c.skipLine();
        } else if (key == "f" || key == "fo") {
            faceStart.push_back(corners.size());
            for (;;) {
                if (!c.moreOnLine()) break;
                const std::string_view t = c.token();
                if (t == "\\") {  // continued on the next line
                    c.skipLine();
                    continue;
                }
                int64_t i = cornerIndex(t, c);
                const auto count = static_cast<int64_t>(out.positions.size());
                if (i == 0 || (i < 0 && -i > count))
                    c.fail("OBJ: a face uses vertex " + std::to_string(i) + " with " +
                           std::to_string(count) +
                           " vertices read (accepted: 1 to the vertex count, or -1 back to "
                           "minus the vertices read so far)");
                if (i > UINT32_MAX) c.fail("OBJ: a face uses vertex " + std::to_string(i));
                i = i > 0 ? i - 1 : count + i;
                if (i > largest) {
                    largest = i;
                    largestLine = c.line();
                }
                corners.push_back(static_cast<uint32_t>(i));
            }
        } else {
            c.skipLine();
        }
    }
    if (largest >= static_cast<int64_t>(out.positions.size()))
        throw InputError(path + ":" + std::to_string(largestLine) + ": OBJ: a face uses vertex " +
                         std::to_string(largest + 1) + ", but the file defines " +
                         std::to_string(out.positions.size()) + " vertices");
    faceStart.push_back(corners.size());
    for (size_t f = 0; f + 1 < faceStart.size(); ++f)
        triangulatePolygon(out.positions,
                           std::span<const uint32_t>(corners.data() + faceStart[f],
                                                     faceStart[f + 1] - faceStart[f]),
                           out.triangles);
    return out;
}

}  // namespace sdft
