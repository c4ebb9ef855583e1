#include "sdftrace/io/image_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfOutputFile.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>

#include "sdftrace/core/error.h"
#include "sdftrace/io/atomic_file.h"

namespace {
constexpr int kPngZlibLevel = 1;  // 1.7x faster than 6 on a 1024x1024 render, 27% larger
// PNG's deflate stream by zlib rather than stb's own compressor: on a 512x512 render stb took 143M
// instructions (callgrind), more than the DDA traced the image in.
unsigned char* zlibCompress(unsigned char* data, int size, int* outSize, int /*quality*/) {
    uLongf bound = compressBound(static_cast<uLong>(size));
    auto* out = static_cast<unsigned char*>(std::malloc(bound));
    if (!out) return nullptr;
    if (compress2(out, &bound, data, static_cast<uLong>(size), kPngZlibLevel) != Z_OK) {
        std::free(out);
        return nullptr;
    }
    *outSize = static_cast<int>(bound);
    return out;
}
}  // namespace

#define STBIW_ZLIB_COMPRESS zlibCompress
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_easy_font.h>
#include <stb_image_write.h>

namespace {
// One PNG filter (Paeth) for every row instead of stb's choice per row, which encodes each row with
// all five filters and keeps the smallest: a sixth of the filtering work, files within 1% of the
// size (a 1024x1024 render: 323,668 against 321,893 bytes).
const int kPngFilterSet = (stbi_write_force_png_filter = 4, 0);
}  // namespace

namespace sdft {

namespace {
// An OpenEXR output stream into memory.
class MemoryStream : public Imf::OStream {
  public:
    MemoryStream() : Imf::OStream("<memory>") {}
    void write(const char c[], int n) override {
        if (m_pos + n > m_bytes.size()) m_bytes.resize(m_pos + n);
        std::memcpy(m_bytes.data() + m_pos, c, n);
        m_pos += n;
    }
    uint64_t tellp() override { return m_pos; }
    void seekp(uint64_t pos) override { m_pos = pos; }
    const std::vector<char>& bytes() const { return m_bytes; }

  private:
    std::vector<char> m_bytes;
    uint64_t m_pos = 0;
};
}  // namespace

ImageFormat imageFormatFromPath(const std::string& path, const std::string& what) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext == ".png") return ImageFormat::Png;
    if (ext == ".exr") return ImageFormat::Exr;
    if (ext == ".pfm") return ImageFormat::Pfm;
    throw InputError(what + " " + path + ": unknown image extension '" + ext +
                     "'; accepted: .png, .exr, .pfm");
}

void writeExr(const std::string& path, int w, int h, int channels, const std::vector<float>& data,
              const std::vector<std::string>& names) {
    MemoryStream stream;
    try {
        Imf::Header header(w, h);
        Imf::FrameBuffer fb;
        const size_t xStride = sizeof(float) * channels, yStride = xStride * w;
        for (int c = 0; c < channels; ++c) {
            header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
            fb.insert(names[c],
                      Imf::Slice(Imf::FLOAT,
                                 const_cast<char*>(reinterpret_cast<const char*>(data.data() + c)),
                                 xStride, yStride));
        }
        Imf::OutputFile file(stream, header);
        file.setFrameBuffer(fb);
        file.writePixels(h);
    } catch (const std::exception& e) {
        throw InputError(path + ": cannot write EXR (" + e.what() + ")");
    }
    // Encoded in memory, then written with every write checked (OpenEXR's file stream does not
    // report a failed flush when it closes).
    writeFileAtomically(path, stream.bytes().data(), stream.bytes().size());
}

void writePfm(const std::string& path, int w, int h, int channels, const std::vector<float>& data) {
    AtomicOutput out(path);
    // Header; a negative scale means little-endian. Rows run bottom to top.
    const std::string header = std::string(channels == 3 ? "PF" : "Pf") + "\n" + std::to_string(w) +
                               " " + std::to_string(h) + "\n-1.0\n";
    out.write(header.data(), header.size());
    for (int y = h - 1; y >= 0; --y)
        out.write(data.data() + static_cast<size_t>(y) * w * channels,
                  static_cast<size_t>(w) * channels * sizeof(float));
    out.commit();
}

void writePng(const std::string& path, int w, int h, int channels,
              const std::vector<unsigned char>& data) {
    // Encoded in memory (stb does not check its own fwrite), then written with every write checked.
    std::vector<unsigned char> png;
    auto append = [](void* context, void* bytes, int size) {
        auto* v = static_cast<std::vector<unsigned char>*>(context);
        v->insert(v->end(), static_cast<unsigned char*>(bytes),
                  static_cast<unsigned char*>(bytes) + size);
    };
    if (!stbi_write_png_to_func(append, &png, w, h, channels, data.data(), w * channels))
        throw InputError(path + ": cannot encode PNG");
    writeFileAtomically(path, png.data(), png.size());
}

namespace {
unsigned char toByte(float v) {
    if (!(v > 0)) return 0;  // also catches NaN
    if (v >= 1) return 255;
    return static_cast<unsigned char>(v * 255.0f + 0.5f);
}
float linearToSrgb(float v) {
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}
// A perceptually ordered dark-blue -> magenta -> orange -> yellow ramp (inferno-like stops).
Vec3 heatColor(float u) {
    static const Vec3 stops[] = {{0.0f, 0.0f, 0.02f},   {0.26f, 0.04f, 0.41f},
                                 {0.58f, 0.15f, 0.40f}, {0.87f, 0.32f, 0.23f},
                                 {0.99f, 0.65f, 0.04f}, {0.99f, 1.0f, 0.64f}};
    u = clampf(u, 0.0f, 1.0f) * 5.0f;
    int i = std::min(4, static_cast<int>(u));
    return lerp(stops[i], stops[i + 1], u - i);
}
std::string formatValue(float v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
}
// Draws text with stb_easy_font (quads), scaled by an integer factor, in white.
void drawText(std::vector<unsigned char>& img, int w, int h, int x, int y, const std::string& text,
              int scale) {
    static char buffer[60000];
    int quads =
        stb_easy_font_print(0, 0, const_cast<char*>(text.c_str()), nullptr, buffer, sizeof buffer);
    const float* v = reinterpret_cast<const float*>(buffer);
    for (int q = 0; q < quads; ++q) {
        const float* quad = v + q * 16;  // 4 vertices x (x, y, z, colour)
        int qx0 = static_cast<int>(quad[0]), qy0 = static_cast<int>(quad[1]);
        int qx1 = static_cast<int>(quad[8]), qy1 = static_cast<int>(quad[9]);
        for (int py = y + qy0 * scale; py < y + qy1 * scale; ++py)
            for (int px = x + qx0 * scale; px < x + qx1 * scale; ++px)
                if (px >= 0 && px < w && py >= 0 && py < h)
                    for (int c = 0; c < 3; ++c)
                        img[3 * (static_cast<size_t>(py) * w + px) + c] = 255;
    }
}
}  // namespace

namespace {
// The sRGB byte of a linear value, directly (a pow per channel).
unsigned char srgbByteDirect(float v) { return toByte(linearToSrgb(clampf(v, 0.f, 1.f))); }

// For each byte c > 0, the smallest float in (0, 1] whose srgbByteDirect is at least c, found by
// bisection over the floats' bit patterns (ordered like the values for positive floats): the
// byte of v is then the number of thresholds <= v, the same byte without a pow.
struct SrgbThresholds {
    float t[256];
    SrgbThresholds() {
        t[0] = 0;
        for (int c = 1; c < 256; ++c) {
            uint32_t lo = 0, hi = std::bit_cast<uint32_t>(1.0f);  // byte(lo) < c <= byte(hi)
            while (hi - lo > 1) {
                const uint32_t mid = lo + (hi - lo) / 2;
                (srgbByteDirect(std::bit_cast<float>(mid)) >= c ? hi : lo) = mid;
            }
            t[c] = std::bit_cast<float>(hi);
        }
    }
};
}  // namespace

// The byte of the smallest float of each 2^16-float bucket of (0, 1] (the float's upper 16 bits):
// a bucket spans less than 2 bytes, so a byte is the bucket's byte plus at most two threshold
// steps.
struct SrgbBuckets {
    static constexpr uint32_t kCount = (0x3f800000u >> 16) + 1;
    unsigned char first[kCount];
    explicit SrgbBuckets(const SrgbThresholds& table) {
        int c = 0;
        for (uint32_t b = 0; b < kCount; ++b) {
            const float lowest = std::bit_cast<float>(b << 16);
            while (c < 255 && table.t[c + 1] <= lowest) ++c;
            first[b] = static_cast<unsigned char>(c);
        }
    }
};

unsigned char srgbByte(float v) {
    static const SrgbThresholds table;
    static const SrgbBuckets buckets(table);
    if (!(v > 0)) return 0;  // also NaN
    if (v >= 1.0f) return 255;
    int c = buckets.first[std::bit_cast<uint32_t>(v) >> 16];
    while (c < 255 && table.t[c + 1] <= v) ++c;
    return static_cast<unsigned char>(c);
}

std::vector<unsigned char> toneMapSrgb(const std::vector<float>& rgb) {
    std::vector<unsigned char> out(rgb.size());
    srgbByte(0.5f);  // the tables built once, before the workers
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rgb.size(), 1 << 16), [&](const auto& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) out[i] = srgbByte(rgb[i]);
    });
    return out;
}

std::vector<unsigned char> heatMapWithLegend(const std::vector<float>& values, int w, int h,
                                             const std::string& label, int& outHeight) {
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (float v : values) {
        if (!std::isfinite(v)) continue;
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    }
    if (!(lo <= hi)) lo = hi = 0;  // no finite value at all
    float range = hi > lo ? hi - lo : 1.0f;
    const int scale = w >= 320 ? 2 : 1;
    const int legend = 16 * scale;
    outHeight = h + legend;
    std::vector<unsigned char> img(static_cast<size_t>(w) * outHeight * 3, 0);
    for (size_t i = 0; i < values.size(); ++i) {
        if (!std::isfinite(values[i])) continue;
        Vec3 c = heatColor((values[i] - lo) / range);
        for (int a = 0; a < 3; ++a) img[3 * i + a] = toByte(c[a]);
    }
    // Legend: the colour ramp across the width, then "min" at the left and "max" at the right.
    for (int y = h; y < h + legend / 2; ++y)
        for (int x = 0; x < w; ++x) {
            Vec3 c = heatColor(static_cast<float>(x) / std::max(1, w - 1));
            for (int a = 0; a < 3; ++a)
                img[3 * (static_cast<size_t>(y) * w + x) + a] = toByte(c[a]);
        }
    std::string left = label + " " + formatValue(lo);
    std::string right = formatValue(hi);
    int textY = h + legend / 2 + 1;
    drawText(img, w, outHeight, 2, textY, left, scale);
    int rightWidth = stb_easy_font_width(const_cast<char*>(right.c_str())) * scale;
    drawText(img, w, outHeight, w - rightWidth - 2, textY, right, scale);
    return img;
}

namespace {

// Motion vectors: EXR channels backward.u / backward.v (Nuke's layer for the motion to the
// previous frame), PFM as RGB with B = 0, PNG as 0.5 + m / (2 max |m|) in R and G.
void writeMotion(const Film& film, ImageFormat format, const std::string& path) {
    const std::vector<float>& m = film.motion;
    if (format == ImageFormat::Exr) {
        writeExr(path, film.width, film.height, 2, m, {"backward.u", "backward.v"});
        return;
    }
    std::vector<float> rgb(3 * film.pixels(), 0.0f);
    float scale = 0;
    for (float v : m) scale = std::max(scale, std::fabs(v));
    for (size_t i = 0; i < film.pixels(); ++i)
        for (int c = 0; c < 2; ++c) rgb[3 * i + c] = m[2 * i + c];
    if (format == ImageFormat::Pfm) {
        writePfm(path, film.width, film.height, 3, rgb);
        return;
    }
    std::vector<unsigned char> bytes(rgb.size());
    for (size_t i = 0; i < rgb.size(); ++i)
        bytes[i] = toByte(i % 3 == 2 ? 0.5f : 0.5f + (scale > 0 ? 0.5f * rgb[i] / scale : 0.0f));
    writePng(path, film.width, film.height, 3, bytes);
}

}  // namespace

void writeAov(const Film& film, Aov aov, const std::string& path) {
    ImageFormat format = imageFormatFromPath(path, std::string("--aov ") + aovName(aov));
    const std::vector<float>& data = film.channel(aov);
    int channels = aovChannels(aov);
    if (aov == Aov::Motion) {
        writeMotion(film, format, path);
    } else if (format == ImageFormat::Exr) {
        std::vector<std::string> names =
            channels == 3 ? std::vector<std::string>{"R", "G", "B"}
                          : std::vector<std::string>{aov == Aov::Depth ? "Z" : "Y"};
        writeExr(path, film.width, film.height, channels, data, names);
    } else if (format == ImageFormat::Pfm) {
        writePfm(path, film.width, film.height, channels, data);
    } else {
        int outHeight = 0;
        const auto rgb = aovPicture(film, aov, true, outHeight);
        writePng(path, film.width, outHeight, 3, rgb);
    }
}

std::vector<unsigned char> aovPicture(const Film& film, Aov aov, bool legend, int& outHeight) {
    const std::vector<float>& data = film.channel(aov);
    outHeight = film.height;
    if (aov == Aov::Color) return toneMapSrgb(data);
    if (aov == Aov::Normal) {
        std::vector<unsigned char> rgb(data.size());
        for (size_t i = 0; i < data.size(); ++i) rgb[i] = toByte(0.5f * data[i] + 0.5f);
        return rgb;
    }
    auto rgb = heatMapWithLegend(data, film.width, film.height, aovName(aov), outHeight);
    if (!legend) {  // the legend strip is below the image
        rgb.resize(static_cast<size_t>(film.width) * film.height * 3);
        outHeight = film.height;
    }
    return rgb;
}

}  // namespace sdft
