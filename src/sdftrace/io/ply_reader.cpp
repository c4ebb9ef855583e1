// PLY (Turk 1994; the Stanford format): a header of elements and their properties, then the
// elements' records in ascii or binary (little- or big-endian). The vertex element's x, y, z and
// the face element's index list are read, of any numeric type; other elements and properties are
// skipped by their declared types. Every declared count is held to the bytes the file has before
// anything is read: a binary file needs at least count × (the record's fixed bytes) per element.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string_view>

#include "polygon_triangulation.h"
#include "sdftrace/io/mapped_file.h"
#include "sdftrace/io/mesh_readers.h"
#include "sdftrace/io/text_cursor.h"

namespace sdft {

namespace {

enum class PlyType { Int8, Uint8, Int16, Uint16, Int32, Uint32, Float32, Float64 };

bool parsePlyType(std::string_view s, PlyType& t) {
    struct Name {
        const char *a, *b;
        PlyType t;
    };
    static constexpr Name kNames[] = {
        {"char", "int8", PlyType::Int8},        {"uchar", "uint8", PlyType::Uint8},
        {"short", "int16", PlyType::Int16},     {"ushort", "uint16", PlyType::Uint16},
        {"int", "int32", PlyType::Int32},       {"uint", "uint32", PlyType::Uint32},
        {"float", "float32", PlyType::Float32}, {"double", "float64", PlyType::Float64}};
    for (const Name& n : kNames)
        if (s == n.a || s == n.b) {
            t = n.t;
            return true;
        }
    return false;
}

size_t typeBytes(PlyType t) {
    switch (t) {
        case PlyType::Int8:
        case PlyType::Uint8:
            return 1;
        case PlyType::Int16:
        case PlyType::Uint16:
            return 2;
        case PlyType::Int32:
        case PlyType::Uint32:
        case PlyType::Float32:
            return 4;
        case PlyType::Float64:
            return 8;
    }
    return 1;
}

struct Property {
    std::string name;
    PlyType type = PlyType::Float32;
    bool list = false;
    PlyType countType = PlyType::Uint8;
};

struct Element {
    std::string name;
    uint64_t count = 0;
    std::vector<Property> props;
    size_t fixedBytes() const {  // a binary record's bytes without its lists' entries
        size_t n = 0;
        for (const Property& p : props) n += typeBytes(p.list ? p.countType : p.type);
        return n;
    }
};

enum class Format { Ascii, Little, Big };

// One binary value of type T at p (byte-swapped where `swap`), as a double.
template <class T>
double binaryAs(const char* p, bool swap) {
    uint8_t b[sizeof(T)];
    std::memcpy(b, p, sizeof b);
    if (swap) std::reverse(b, b + sizeof b);
    T v;
    std::memcpy(&v, b, sizeof v);
    return static_cast<double>(v);
}

double binaryValue(const char* p, PlyType t, bool swap) {
    switch (t) {
        case PlyType::Int8:
            return binaryAs<int8_t>(p, swap);
        case PlyType::Uint8:
            return binaryAs<uint8_t>(p, swap);
        case PlyType::Int16:
            return binaryAs<int16_t>(p, swap);
        case PlyType::Uint16:
            return binaryAs<uint16_t>(p, swap);
        case PlyType::Int32:
            return binaryAs<int32_t>(p, swap);
        case PlyType::Uint32:
            return binaryAs<uint32_t>(p, swap);
        case PlyType::Float32:
            return binaryAs<float>(p, swap);
        case PlyType::Float64:
            return binaryAs<double>(p, swap);
    }
    return 0;
}

class PlyReader {
  public:
    explicit PlyReader(const std::string& path) : m_path(path), m_file(path) {}

    MeshArrays read() {
        readHeader();
        checkSizes();
        MeshArrays out;
        for (const Element& e : m_elements) readElement(e, out);
        if (m_vertex < 0) fail("it has no vertex element; accepted: 'element vertex N'");
        return out;
    }

  private:
    [[noreturn]] void fail(const std::string& what) const {
        throw InputError(m_path + ": PLY: " + what);
    }

    void readHeader() {
        const char* p = m_file.data();
        const char* end = p + m_file.size();
        TextCursor c(p, end, m_path);
        auto nextLine = [&](std::string_view& line) {
            const char* start = c.position();
            if (start >= end) fail("the header has no 'end_header' line (is the file cut short?)");
            c.skipLine();
            line = std::string_view(start, static_cast<size_t>(c.position() - start));
            while (!line.empty() && (line.back() == '\n' || line.back() == '\r' ||
                                     line.back() == ' ' || line.back() == '\t'))
                line.remove_suffix(1);
        };
        std::string_view line;
        nextLine(line);
        if (line != "ply") fail("the file does not start with the line 'ply'");
        bool haveFormat = false;
        for (;;) {
            nextLine(line);
            if (line == "end_header") break;
            TextCursor words(line.data(), line.data() + line.size(), m_path);
            const std::string_view key = words.token();
            if (key == "comment" || key == "obj_info" || key.empty()) continue;
            if (key == "format") {
                const std::string_view f = words.token();
                if (f == "ascii")
                    m_format = Format::Ascii;
                else if (f == "binary_little_endian")
                    m_format = Format::Little;
                else if (f == "binary_big_endian")
                    m_format = Format::Big;
                else
                    fail("unknown format '" + TextCursor::printable(f.substr(0, 32)) +
                         "'; accepted: ascii, binary_little_endian, binary_big_endian");
                haveFormat = true;
            } else if (key == "element") {
                Element e;
                e.name = TextCursor::printable(words.token().substr(0, 64));
                const std::string_view n = words.token();
                uint64_t count = 0;
                const auto [ptr, ec] = std::from_chars(n.data(), n.data() + n.size(), count);
                if (e.name.empty() || ec != std::errc() || ptr != n.data() + n.size())
                    fail("bad header line '" + TextCursor::printable(line.substr(0, 60)) +
                         "'; accepted: 'element NAME COUNT'");
                e.count = count;
                m_elements.push_back(std::move(e));
            } else if (key == "property") {
                if (m_elements.empty()) fail("a property comes before any element");
                Property prop;
                std::string_view t = words.token();
                if (t == "list") {
                    prop.list = true;
                    if (!parsePlyType(words.token(), prop.countType) ||
                        !parsePlyType(words.token(), prop.type))
                        fail("bad header line '" + TextCursor::printable(line.substr(0, 60)) +
                             "'; accepted: 'property list COUNT_TYPE TYPE NAME'");
                    if (prop.countType == PlyType::Float32 || prop.countType == PlyType::Float64)
                        fail("a list's count type must be an integer type");
                } else if (!parsePlyType(t, prop.type)) {
                    fail("unknown property type '" + TextCursor::printable(t.substr(0, 32)) +
                         "'; accepted: char, uchar, short, ushort, int, uint, float, double "
                         "(or int8 ... float64)");
                }
                prop.name = std::string(words.token());
                m_elements.back().props.push_back(std::move(prop));
            } else {
                fail("unknown header line '" + TextCursor::printable(line.substr(0, 60)) + "'");
            }
        }
        if (!haveFormat) fail("the header has no 'format' line");
        m_body = m_binary = c.position();
        m_end = end;
        findMeshElements();
    }

    // The vertex element with its x, y, z, and the face element with its index list.
    void findMeshElements() {
        for (size_t i = 0; i < m_elements.size(); ++i) {
            Element& e = m_elements[i];
            if (e.name == "vertex" && m_vertex < 0) {
                m_vertex = static_cast<int>(i);
                for (size_t k = 0; k < e.props.size(); ++k) {
                    const Property& p = e.props[k];
                    if (p.list) continue;
                    if (p.name == "x") m_xyz[0] = static_cast<int>(k);
                    if (p.name == "y") m_xyz[1] = static_cast<int>(k);
                    if (p.name == "z") m_xyz[2] = static_cast<int>(k);
                }
                if (m_xyz[0] < 0 || m_xyz[1] < 0 || m_xyz[2] < 0)
                    fail("the vertex element has no x, y and z properties");
                if (e.count > UINT32_MAX)
                    fail("it declares " + std::to_string(e.count) +
                         " vertices; accepted: at most 4294967295");
            } else if (e.name == "face" && m_face < 0) {
                m_face = static_cast<int>(i);
                for (size_t k = 0; k < e.props.size() && m_indices < 0; ++k)
                    if (e.props[k].list &&
                        (e.props[k].name == "vertex_indices" || e.props[k].name == "vertex_index"))
                        m_indices = static_cast<int>(k);
                for (size_t k = 0; k < e.props.size() && m_indices < 0; ++k)
                    if (e.props[k].list) m_indices = static_cast<int>(k);
                if (m_indices < 0) fail("the face element has no list of vertex indices");
            }
        }
    }

    // Each record takes at least its fixed bytes (binary) or two bytes per property (ascii: a
    // digit and a separator), and at least one byte (an element without properties): a count the
    // rest of the file cannot hold is refused before anything is read or allocated, and no record
    // loop runs longer than the file.
    void checkSizes() const {
        const double body = static_cast<double>(m_end - m_body);
        double need = 0;
        std::string counts;
        for (const Element& e : m_elements) {
            const double per = m_format == Format::Ascii
                                   ? 2.0 * static_cast<double>(std::max<size_t>(1, e.props.size()))
                                   : static_cast<double>(std::max<size_t>(1, e.fixedBytes()));
            need += static_cast<double>(e.count) * per;
            if (!counts.empty()) counts += " and ";
            counts += std::to_string(e.count) + " " + e.name;
        }
        if (need > body + 1)
            fail("the header declares " + counts + " records, at least " + formatCount(need) +
                 " bytes, but " + formatCount(body) + " bytes follow it (is the file cut short?)");
    }

    void readElement(const Element& e, MeshArrays& out) {
        const bool vertex = m_vertex >= 0 && &e == &m_elements[static_cast<size_t>(m_vertex)];
        const bool face = m_face >= 0 && &e == &m_elements[static_cast<size_t>(m_face)];
        if (vertex) out.positions.reserve(e.count);  // checkSizes held it to the file's bytes
        const uint64_t vertexCount =
            m_vertex >= 0 ? m_elements[static_cast<size_t>(m_vertex)].count : 0;
        std::vector<uint32_t> poly;
        double xyz[3] = {0, 0, 0};
        for (uint64_t r = 0; r < e.count; ++r) {
            for (size_t k = 0; k < e.props.size(); ++k) {
                const Property& p = e.props[k];
                if (!p.list) {
                    const double v = value(p.type, e, r);
                    if (vertex)
                        for (int a = 0; a < 3; ++a)
                            if (m_xyz[a] == static_cast<int>(k)) xyz[a] = v;
                    continue;
                }
                const double n = value(p.countType, e, r);
                if (!(n >= 0) || n > 1e9)
                    fail(e.name + " " + std::to_string(r) + ": a list of " + formatCount(n) +
                         " entries");
                const auto count = static_cast<uint64_t>(n);
                const bool indices = face && static_cast<int>(k) == m_indices;
                if (indices) poly.clear();
                if (m_format != Format::Ascii &&
                    count * typeBytes(p.type) > static_cast<uint64_t>(m_end - m_binary))
                    fail(e.name + " " + std::to_string(r) + ": a list of " + std::to_string(count) +
                         " entries runs past the end of the file (is it "
                         "cut short?)");
                for (uint64_t j = 0; j < count; ++j) {
                    const double v = value(p.type, e, r);
                    if (!indices) continue;
                    if (!(v >= 0) || v >= static_cast<double>(vertexCount) || v != std::floor(v))
                        fail("face " + std::to_string(r) + " uses vertex " + formatCount(v) +
                             ", but there are " + std::to_string(vertexCount) +
                             " vertices (accepted: whole numbers below the vertex count)");
                    poly.push_back(static_cast<uint32_t>(v));
                }
                if (indices)  // points and lines make no triangle
                    triangulatePolygon(out.positions, poly, out.triangles);
            }
            if (vertex)
                out.positions.push_back({toFloatCoordinate(xyz[0]), toFloatCoordinate(xyz[1]),
                                         toFloatCoordinate(xyz[2])});
        }
    }

    // A count or index as read (any double: no cast that could overflow).
    static std::string formatCount(double v) {
        char buf[48];
        std::snprintf(buf, sizeof buf, v >= 0 && v < 1e18 ? "%.0f" : "%.17g", v);
        return buf;
    }

    // The next value of element e's record r.
    double value(PlyType t, const Element& e, uint64_t r) {
        if (m_format == Format::Ascii) {  // any type: a number
            if (!m_ascii) m_ascii.emplace(m_body, m_end, m_path);
            const std::string_view tok = m_ascii->token();
            double v = 0;
            const char* first = tok.data();
            if (!tok.empty() && *first == '+') ++first;
            const auto [ptr, ec] = std::from_chars(first, tok.data() + tok.size(), v);
            if (tok.empty())
                fail(e.name + " " + std::to_string(r) +
                     ": the file ends before its last record (is it cut short?)");
            if (ec != std::errc() || ptr != tok.data() + tok.size())
                fail(e.name + " " + std::to_string(r) + ": '" +
                     TextCursor::printable(tok.substr(0, 32)) + "' is not a number");
            return v;
        }
        const size_t n = typeBytes(t);
        if (static_cast<size_t>(m_end - m_binary) < n)
            fail(e.name + " " + std::to_string(r) +
                 ": the file ends before its last record (is it cut short?)");
        const double v = binaryValue(m_binary, t, m_format == Format::Big);
        m_binary += n;
        return v;
    }

    std::string m_path;
    MappedFile m_file;
    Format m_format = Format::Ascii;
    std::vector<Element> m_elements;
    const char* m_body = nullptr;
    const char* m_end = nullptr;
    const char* m_binary = nullptr;  // the next binary value
    std::optional<TextCursor> m_ascii;
    int m_vertex = -1, m_face = -1, m_indices = -1;
    int m_xyz[3] = {-1, -1, -1};
};

}  // namespace

MeshArrays readPly(const std::string& path) { return PlyReader(path).read(); }

}  // namespace sdft
