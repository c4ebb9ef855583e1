#include "sdftrace/io/sdfgen_io.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "dense_shape.h"
#include "sdftrace/core/error.h"
#include "sdftrace/io/atomic_file.h"

namespace sdft {

namespace {

// Numbers one after another through a text held in memory, with the line for messages.
class NumberReader {
  public:
    NumberReader(const std::string& text, const std::string& path) : m_text(text), m_path(path) {}

    template <class T>
    T next(const char* what) {
        skipSpace();
        if (m_pos >= m_text.size()) fail(std::string("the file ends before ") + what);
        T v{};
        const char* begin = m_text.data() + m_pos;
        const char* end = m_text.data() + m_text.size();
        auto [ptr, ec] = std::from_chars(begin, end, v);
        if (ec != std::errc() || (ptr < end && !std::isspace(static_cast<unsigned char>(*ptr)))) {
            const char* stop = begin;
            while (stop < end && !std::isspace(static_cast<unsigned char>(*stop)) &&
                   stop - begin < 24)
                ++stop;
            fail(std::string("expected ") + what + ", found '" + std::string(begin, stop) + "'");
        }
        m_pos = static_cast<size_t>(ptr - m_text.data());
        return v;
    }
    bool atEnd() {
        skipSpace();
        return m_pos >= m_text.size();
    }
    // The most numbers the rest of the text can hold: each is a character and a separator.
    size_t mostNumbersLeft() const { return (m_text.size() - m_pos + 1) / 2; }
    [[noreturn]] void fail(const std::string& what) const {
        throw InputError(m_path + ": line " + std::to_string(m_line) + ": " + what +
                         " (SDFGen format: 'ni nj nk', the origin, dx, then ni*nj*nk values)");
    }

  private:
    void skipSpace() {
        while (m_pos < m_text.size() && std::isspace(static_cast<unsigned char>(m_text[m_pos]))) {
            if (m_text[m_pos] == '\n') ++m_line;
            ++m_pos;
        }
    }
    const std::string& m_text;
    const std::string& m_path;
    size_t m_pos = 0;
    int64_t m_line = 1;
};

std::string readWholeFile(const std::string& path) {
    std::error_code ec;
    const auto bytes = std::filesystem::file_size(path, ec);
    std::ifstream in(path, std::ios::binary);
    if (ec || !in) throw InputError(path + ": cannot open (does it exist and is it readable?)");
    checkMemoryBudget(static_cast<double>(bytes), path, "the file's text", "resample it coarser");
    std::string text(bytes, '\0');
    if (!in.read(text.data(), static_cast<std::streamsize>(bytes)))
        throw InputError(path + ": cannot read the file");
    return text;
}

}  // namespace

Grid loadSdfgen(const std::string& path) {
    const std::string text = readWholeFile(path);
    NumberReader r(text, path);
    int64_t dims[3];
    for (int64_t& d : dims) d = r.next<int64_t>("a sample count (ni nj nk)");
    double origin[3];
    for (double& o : origin) o = r.next<double>("the origin (three numbers)");
    const double dx = r.next<double>("the spacing dx");
    const GridShape shape = io_detail::denseShape(dims, origin, dx, path);
    // Held to the file's length before the samples are allocated: a 20-byte file cannot ask for
    // gigabytes.
    if (shape.vertexCount() > r.mostNumbersLeft())
        r.fail("the file ends before its " + std::to_string(shape.vertexCount()) + " values (its " +
               std::to_string(text.size()) + " bytes hold at most " +
               std::to_string(r.mostNumbersLeft()) + ")");
    std::vector<float> samples(shape.vertexCount());
    for (size_t i = 0; i < samples.size(); ++i) {
        samples[i] = r.next<float>("a distance value");
        if (!std::isfinite(samples[i])) r.fail("non-finite distance value");
    }
    if (!r.atEnd()) r.fail("more values than ni*nj*nk = " + std::to_string(samples.size()));
    return Grid::dense(shape, std::move(samples));
}

void saveSdfgen(const Grid& grid, const std::string& path) {
    const GridShape& s = grid.shape();
    const std::vector<float> samples = grid.vertexSamples();
    AtomicOutput out(path);
    char header[256];
    const int n = std::snprintf(header, sizeof header, "%d %d %d\n%.9g %.9g %.9g\n%.9g\n",
                                s.vertices(0), s.vertices(1), s.vertices(2), s.origin.x, s.origin.y,
                                s.origin.z, s.voxelSize);
    out.write(header, static_cast<size_t>(n));
    std::vector<char> buffer;
    buffer.reserve(1 << 20);
    char number[32];
    for (size_t i = 0; i < samples.size(); ++i) {
        auto [end, ec] = std::to_chars(number, number + sizeof number, samples[i]);
        buffer.insert(buffer.end(), number, end);
        buffer.push_back('\n');
        if (buffer.size() >= (1 << 20) - 64 || i + 1 == samples.size()) {
            out.write(buffer.data(), buffer.size());
            buffer.clear();
        }
    }
    out.commit();
}

}  // namespace sdft
