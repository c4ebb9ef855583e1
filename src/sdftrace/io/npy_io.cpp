#include "sdftrace/io/npy_io.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>

#include "mapped_file.h"
#include "mesh_readers.h"
#include "sdftrace/core/error.h"
#include "sdftrace/io/atomic_file.h"
#include "text_cursor.h"

namespace sdft {

namespace {

// The header dictionary of a .npy file: {'descr': '<f8', 'fortran_order': False, 'shape': (N, 3), }
struct NpyHeader {
    std::string descr;
    bool fortran = false;
    std::vector<uint64_t> shape;
};

// The value text after 'key': in the dictionary (a quoted string, a tuple or a word).
std::string dictValue(const std::string& dict, const std::string& key, const std::string& path) {
    size_t k = dict.find("'" + key + "'");
    if (k == std::string::npos) k = dict.find("\"" + key + "\"");
    if (k == std::string::npos)
        throw InputError(path + ": .npy header has no '" + key +
                         "' (expected numpy's {'descr', 'fortran_order', 'shape'} dictionary)");
    size_t p = dict.find(':', k + key.size() + 2);
    if (p == std::string::npos)
        throw InputError(path + ": .npy header: no value for '" + key + "'");
    ++p;
    while (p < dict.size() && dict[p] == ' ') ++p;
    if (p >= dict.size()) throw InputError(path + ": .npy header: no value for '" + key + "'");
    const char open = dict[p];
    if (open == '\'' || open == '"') {
        const size_t e = dict.find(open, p + 1);
        if (e == std::string::npos) throw InputError(path + ": .npy header: unterminated string");
        return dict.substr(p + 1, e - p - 1);
    }
    if (open == '(') {
        const size_t e = dict.find(')', p);
        if (e == std::string::npos) throw InputError(path + ": .npy header: unterminated shape");
        return dict.substr(p + 1, e - p - 1);
    }
    size_t e = p;
    while (e < dict.size() && std::isalpha(static_cast<unsigned char>(dict[e]))) ++e;
    return dict.substr(p, e - p);
}

NpyHeader parseHeader(const std::string& dict, const std::string& path) {
    NpyHeader h;
    h.descr = dictValue(dict, "descr", path);
    const std::string f = dictValue(dict, "fortran_order", path);
    if (f != "True" && f != "False")
        throw InputError(path + ": .npy header: fortran_order '" + f + "'; expected True or False");
    h.fortran = f == "True";
    const std::string shape = dictValue(dict, "shape", path);
    std::string s = shape;
    std::replace(s.begin(), s.end(), ',', ' ');
    TextCursor dims(s.data(), s.data() + s.size(), path + ": .npy header: shape");
    while (!dims.atEnd()) {
        const int64_t d = dims.integer("dimension");
        if (d < 0) throw InputError(path + ": .npy header: negative dimension in shape");
        h.shape.push_back(static_cast<uint64_t>(d));
    }
    return h;
}

// Reads value i of the array's element type as double.
struct Element {
    char kind;  // 'f', 'i', 'u', 'b'
    int size;
    bool swap;
    double read(const uint8_t* p) const {
        uint8_t b[8];
        std::memcpy(b, p, size);
        if (swap) std::reverse(b, b + size);
        switch (kind) {
            case 'f': {
                if (size == 4) {
                    float v;
                    std::memcpy(&v, b, 4);
                    return v;
                }
                double v;
                std::memcpy(&v, b, 8);
                return v;
            }
            case 'i': {
                int64_t v = 0;
                if (size == 1)
                    v = static_cast<int8_t>(b[0]);
                else if (size == 2) {
                    int16_t t;
                    std::memcpy(&t, b, 2);
                    v = t;
                } else if (size == 4) {
                    int32_t t;
                    std::memcpy(&t, b, 4);
                    v = t;
                } else
                    std::memcpy(&v, b, 8);
                return static_cast<double>(v);
            }
            case 'u': {
                uint64_t v = 0;
                std::memcpy(&v, b, size);  // little-endian host
                return static_cast<double>(v);
            }
            default:
                return b[0] ? 1.0 : 0.0;
        }
    }
};

Element elementOf(const std::string& descr, const std::string& path) {
    auto bad = [&] {
        return InputError(path + ": .npy dtype '" + descr +
                          "' is not supported; expected float32/float64 ('<f4', '<f8'), "
                          "integers ('<i1'...'<i8', '<u1'...'<u8') or bool ('|b1')");
    };
    if (descr.size() < 3) throw bad();
    const char order = descr[0], kind = descr[1];
    int size = 0;
    const std::string digits = descr.substr(2);
    if (digits == "1")
        size = 1;
    else if (digits == "2")
        size = 2;
    else if (digits == "4")
        size = 4;
    else if (digits == "8")
        size = 8;
    else
        throw bad();
    if (order != '<' && order != '>' && order != '|' && order != '=') throw bad();
    if (kind == 'f' && size != 4 && size != 8) throw bad();
    if (kind == 'b' && size != 1) throw bad();
    if (kind != 'f' && kind != 'i' && kind != 'u' && kind != 'b') throw bad();
    return {kind, size, order == '>' && size > 1};
}

}  // namespace

namespace {

// A .npy file (magic already matched) into t.
void parseNpy(std::string_view bytes, const std::string& path, size_t cols, PointTable& t) {
    if (bytes.size() < 10) throw InputError(path + ": .npy file cut short in its header");
    const int major = static_cast<uint8_t>(bytes[6]);
    if (major < 1 || major > 3)
        throw InputError(path + ": .npy format version " + std::to_string(major) +
                         "; versions 1 to 3 are read");
    size_t headerLen, start;
    if (major == 1) {
        headerLen = static_cast<uint8_t>(bytes[8]) | (static_cast<uint8_t>(bytes[9]) << 8);
        start = 10;
    } else {
        if (bytes.size() < 12) throw InputError(path + ": .npy file cut short in its header");
        headerLen = 0;
        for (int i = 0; i < 4; ++i)
            headerLen |= static_cast<size_t>(static_cast<uint8_t>(bytes[8 + i])) << (8 * i);
        start = 12;
    }
    if (headerLen > bytes.size() - start)
        throw InputError(path + ": .npy header of " + std::to_string(headerLen) +
                         " bytes runs past the end of the file");
    const NpyHeader h = parseHeader(std::string(bytes.substr(start, headerLen)), path);
    const Element e = elementOf(h.descr, path);
    if (h.shape.size() != 2 || h.shape[1] != cols)
        throw InputError(path + ": array of shape (" +
                         [&] {
                             std::string s;
                             for (size_t i = 0; i < h.shape.size(); ++i)
                                 s += (i ? ", " : "") + std::to_string(h.shape[i]);
                             return s + (h.shape.size() == 1 ? ",)" : ")");
                         }() +
                         "; expected N x " + std::to_string(cols));
    const uint64_t rows = h.shape[0];
    const size_t data = start + headerLen;
    if (rows > (bytes.size() - data) / (cols * e.size) ||
        rows * cols * e.size != bytes.size() - data)
        throw InputError(path + ": " + std::to_string(rows) + " x " + std::to_string(cols) +
                         " values of " + std::to_string(e.size) + " bytes need " +
                         std::to_string(rows * cols * e.size) + " bytes of data; the file has " +
                         std::to_string(bytes.size() - data));
    t.rows = rows;
    t.single = e.kind == 'f' && e.size == 4;
    t.values.resize(rows * cols);
    const auto* p = reinterpret_cast<const uint8_t*>(bytes.data() + data);
    for (size_t r = 0; r < rows; ++r)
        for (size_t c = 0; c < cols; ++c)
            t.values[r * cols + c] = e.read(p + e.size * (h.fortran ? c * rows + r : r * cols + c));
}

// CSV text into t.
void parseCsv(std::string_view bytes, const std::string& path, size_t cols, PointTable& t) {
    // CSV: commas, semicolons and tabs are separators; a first line that is not numbers is
    // the header.
    std::string text(bytes);
    std::replace_if(
        text.begin(), text.end(), [](char ch) { return ch == ',' || ch == ';'; }, ' ');
    TextCursor c(text.data(), text.data() + text.size(), path);
    c.allowComments(true);
    c.skipSpace();
    if (!c.atEnd()) {
        const std::string_view first = c.peekToken();
        double v;
        const char* b = first.data() + (!first.empty() && first[0] == '+');
        const auto [ptr, ec] = std::from_chars(b, first.data() + first.size(), v);
        if (ec != std::errc() || ptr != first.data() + first.size()) c.skipLine();
    }
    while (!c.atEnd()) {
        for (size_t k = 0; k < cols; ++k) {
            if (!c.moreOnLine())
                c.fail("expected " + std::to_string(cols) + " numbers on the line, found " +
                       std::to_string(k));
            t.values.push_back(c.number("value"));
        }
        if (c.moreOnLine()) c.fail("more than " + std::to_string(cols) + " numbers on the line");
        ++t.rows;
    }
}

}  // namespace

PointTable parsePointTable(std::string_view bytes, const std::string& path, size_t cols) {
    PointTable t;
    t.cols = cols;
    if (bytes.size() >= 6 && std::memcmp(bytes.data(), "\x93NUMPY", 6) == 0)
        parseNpy(bytes, path, cols, t);
    else
        parseCsv(bytes, path, cols, t);
    for (size_t i = 0; i < t.values.size(); ++i)
        if (!std::isfinite(t.values[i]))
            throw InputError(path + ": row " + std::to_string(i / cols) +
                             " is not finite; expected finite numbers");
    return t;
}

PointTable readPointTable(const std::string& path, size_t cols) {
    const MappedFile file(path);
    return parsePointTable({file.data(), file.size()}, path, cols);
}

std::string npyBytes(const NamedArray& a) {
    const char kind = a.kind == 'b' ? 'b' : a.kind;
    std::string descr =
        a.kind == 'b' ? "|b1" : std::string("<") + kind + std::to_string(a.itemsize);
    std::string shape =
        "(" + std::to_string(a.rows) + (a.cols ? ", " + std::to_string(a.cols) : ",") + ")";
    std::string dict =
        "{'descr': '" + descr + "', 'fortran_order': False, 'shape': " + shape + ", }";
    // Padded with spaces and a newline so that the data starts at a multiple of 64 bytes.
    const bool v2 = dict.size() + 11 > 65535;
    const size_t prefix = v2 ? 12 : 10;
    const size_t total = (prefix + dict.size() + 1 + 63) / 64 * 64;
    dict.append(total - prefix - dict.size() - 1, ' ');
    dict += '\n';
    std::string out = "\x93NUMPY";
    out += static_cast<char>(v2 ? 2 : 1);
    out += '\0';
    const size_t len = dict.size();
    for (size_t i = 0; i < (v2 ? 4u : 2u); ++i) out += static_cast<char>((len >> (8 * i)) & 0xFF);
    out += dict;
    out.append(reinterpret_cast<const char*>(a.bytes.data()), a.bytes.size());
    return out;
}

namespace {

uint32_t crc32(const std::string& s) {
    static const std::array<uint32_t, 256> table = [] {
        std::array<uint32_t, 256> t{};
        for (uint32_t i = 0; i < 256; ++i) {
            uint32_t c = i;
            for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
            t[i] = c;
        }
        return t;
    }();
    uint32_t c = 0xFFFFFFFFu;
    for (unsigned char b : s) c = table[(c ^ b) & 0xFF] ^ (c >> 8);
    return c ^ 0xFFFFFFFFu;
}

void put16(std::string& s, uint32_t v) {
    s += static_cast<char>(v & 0xFF);
    s += static_cast<char>((v >> 8) & 0xFF);
}
void put32(std::string& s, uint32_t v) {
    put16(s, v & 0xFFFF);
    put16(s, v >> 16);
}

// A zip archive of stored (uncompressed) members, as numpy.savez writes one.
void writeNpz(AtomicOutput& out, const std::vector<NamedArray>& arrays) {
    std::string central;
    uint64_t offset = 0;
    for (const NamedArray& a : arrays) {
        const std::string data = npyBytes(a);
        const std::string name = a.name + ".npy";
        if (data.size() >= 0xFFFFFFFFull || offset >= 0xFFFFFFFFull)
            throw InputError(out.finalPath() +
                             ": over 4 GiB in one .npz (no ZIP64 here); write fewer points per "
                             "file or one .npy per array");
        const uint32_t crc = crc32(data);
        std::string local;
        put32(local, 0x04034b50);
        put16(local, 20);    // version needed
        put16(local, 0);     // flags
        put16(local, 0);     // stored
        put16(local, 0);     // time
        put16(local, 0x21);  // date: 1980-01-01
        put32(local, crc);
        put32(local, static_cast<uint32_t>(data.size()));
        put32(local, static_cast<uint32_t>(data.size()));
        put16(local, static_cast<uint32_t>(name.size()));
        put16(local, 0);
        local += name;
        put32(central, 0x02014b50);
        put16(central, 20);
        put16(central, 20);
        put16(central, 0);
        put16(central, 0);
        put16(central, 0);
        put16(central, 0x21);
        put32(central, crc);
        put32(central, static_cast<uint32_t>(data.size()));
        put32(central, static_cast<uint32_t>(data.size()));
        put16(central, static_cast<uint32_t>(name.size()));
        put16(central, 0);
        put16(central, 0);
        put16(central, 0);
        put16(central, 0);
        put32(central, 0);
        put32(central, static_cast<uint32_t>(offset));
        central += name;
        out.write(local.data(), local.size());
        out.write(data.data(), data.size());
        offset += local.size() + data.size();
    }
    if (offset >= 0xFFFFFFFFull)
        throw InputError(out.finalPath() + ": over 4 GiB in one .npz (no ZIP64 here)");
    std::string end;
    put32(end, 0x06054b50);
    put16(end, 0);
    put16(end, 0);
    put16(end, static_cast<uint32_t>(arrays.size()));
    put16(end, static_cast<uint32_t>(arrays.size()));
    put32(end, static_cast<uint32_t>(central.size()));
    put32(end, static_cast<uint32_t>(offset));
    put16(end, 0);
    out.write(central.data(), central.size());
    out.write(end.data(), end.size());
}

// Element `k` of row r of the array as CSV text.
std::string csvValue(const NamedArray& a, size_t index) {
    char buf[40];
    const uint8_t* p = a.bytes.data() + index * a.itemsize;
    if (a.kind == 'b') return *p ? "1" : "0";
    if (a.kind == 'i') {
        int64_t v;
        std::memcpy(&v, p, 8);
        return std::to_string(v);
    }
    if (a.itemsize == 4) {
        float v;
        std::memcpy(&v, p, 4);
        std::snprintf(buf, sizeof buf, "%.9g", v);
    } else {
        double v;
        std::memcpy(&v, p, 8);
        std::snprintf(buf, sizeof buf, "%.17g", v);
    }
    return buf;
}

void writeCsv(AtomicOutput& out, const std::vector<NamedArray>& arrays) {
    static const char* axes[] = {"x", "y", "z"};
    std::string line;
    for (const NamedArray& a : arrays)
        for (size_t c = 0; c < std::max<size_t>(a.cols, 1); ++c) {
            if (!line.empty()) line += ',';
            line += a.name;
            if (a.cols)
                line += std::string("_") + (a.cols <= 3 ? axes[c] : std::to_string(c).c_str());
        }
    line += '\n';
    out.write(line.data(), line.size());
    const size_t rows = arrays.empty() ? 0 : arrays[0].rows;
    for (size_t r = 0; r < rows; ++r) {
        line.clear();
        for (const NamedArray& a : arrays)
            for (size_t c = 0; c < std::max<size_t>(a.cols, 1); ++c) {
                if (!line.empty()) line += ',';
                line += csvValue(a, r * std::max<size_t>(a.cols, 1) + c);
            }
        line += '\n';
        out.write(line.data(), line.size());
    }
}

}  // namespace

void writeArrays(const std::string& path, const std::vector<NamedArray>& arrays) {
    static_assert(std::endian::native == std::endian::little, "the .npy writer assumes it");
    AtomicOutput out(path);
    const std::string ext = lowerExtension(path);
    if (ext == ".npz") {
        writeNpz(out, arrays);
    } else if (ext == ".npy") {
        if (arrays.size() != 1)
            throw InputError(path + ": a .npy file holds one array and the query gives " +
                             std::to_string(arrays.size()) + "; write .npz (or .csv)");
        const std::string data = npyBytes(arrays[0]);
        out.write(data.data(), data.size());
    } else if (ext == ".csv") {
        writeCsv(out, arrays);
    } else {
        throw InputError(path + ": unknown output extension; expected .npz, .npy or .csv");
    }
    out.commit();
}

}  // namespace sdft
