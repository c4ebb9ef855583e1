#include "sdftrace/io/image_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "sdftrace/core/error.h"

namespace sdft {
namespace {

std::string tempName(const std::string& name) {
    return (std::filesystem::temp_directory_path() /
            ("sdftrace-io-" + std::to_string(::getpid()) + "-" + name))
        .string();
}

TEST(ImageIo, ExrRoundTripKeepsFloatsAndInfinity) {
    Film film(5, 3);
    for (size_t i = 0; i < film.pixels(); ++i) film.depth[i] = 0.25f * i;
    film.depth[7] = std::numeric_limits<float>::infinity();
    std::string path = tempName("depth.exr");
    writeAov(film, Aov::Depth, path);

    Imf::InputFile in(path.c_str());
    auto dw = in.header().dataWindow();
    int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
    ASSERT_EQ(w, 5);
    ASSERT_EQ(h, 3);
    ASSERT_NE(in.header().channels().findChannel("Z"), nullptr);
    std::vector<float> back(w * h);
    Imf::FrameBuffer fb;
    fb.insert("Z", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(back.data()), sizeof(float),
                              sizeof(float) * w));
    in.setFrameBuffer(fb);
    in.readPixels(dw.min.y, dw.max.y);
    for (int i = 0; i < w * h; ++i) EXPECT_EQ(back[i], film.depth[i]) << i;
    std::filesystem::remove(path);
}

TEST(ImageIo, PfmIsBottomUpLittleEndianWithHeader) {
    Film film(2, 2);
    film.color = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};  // rows: top (1..6), bottom (7..12)
    std::string path = tempName("c.pfm");
    writeAov(film, Aov::Color, path);
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    std::string data = ss.str();
    std::string header = "PF\n2 2\n-1.0\n";
    ASSERT_EQ(data.substr(0, header.size()), header);
    float first;
    std::memcpy(&first, data.data() + header.size(), 4);
    EXPECT_EQ(first, 7.0f);  // the bottom row comes first
    std::filesystem::remove(path);
}

TEST(ImageIo, HeatMapSpansTheFiniteRangeAndAddsALegend) {
    std::vector<float> v = {0, 5, 10, std::numeric_limits<float>::infinity()};
    int outH = 0;
    auto rgb = heatMapWithLegend(v, 4, 1, "steps", outH);
    EXPECT_GT(outH, 1);
    ASSERT_EQ(rgb.size(), static_cast<size_t>(4 * outH * 3));
    // Lowest value darkest, highest brightest, non-finite black.
    auto luminance = [&](int i) { return rgb[3 * i] + rgb[3 * i + 1] + rgb[3 * i + 2]; };
    EXPECT_LT(luminance(0), luminance(1));
    EXPECT_LT(luminance(1), luminance(2));
    EXPECT_EQ(luminance(3), 0);
}

TEST(ImageIo, ToneMappingIsSrgbAndClamps) {
    auto bytes = toneMapSrgb({0.0f, 0.5f, 1.0f, 7.0f, -1.0f, std::nanf("")});
    EXPECT_EQ(bytes[0], 0);
    EXPECT_EQ(bytes[1], 188);  // sRGB(0.5) = 0.735
    EXPECT_EQ(bytes[2], 255);
    EXPECT_EQ(bytes[3], 255);
    EXPECT_EQ(bytes[4], 0);
    EXPECT_EQ(bytes[5], 0);
}

TEST(ImageIo, FailedWriteLeavesNoFile) {
    Film film(2, 2);
    EXPECT_THROW(writeAov(film, Aov::Color, "/nonexistent-dir/x.png"), InputError);
    EXPECT_THROW(writeAov(film, Aov::Color, "/nonexistent-dir/x.exr"), InputError);
    EXPECT_THROW(writeAov(film, Aov::Color, tempName("x.jpg")), InputError);
    EXPECT_FALSE(std::filesystem::exists(tempName("x.jpg")));
}

}  // namespace
}  // namespace sdft

namespace sdft {
namespace {

// The table lookup gives the byte of the formula (IEC 61966-2-1 with round-to-nearest) for every
// float in [0, 1] stepped finely, around every byte boundary, and at the edges.
TEST(ImageIo, SrgbBytesMatchTheFormula) {
    auto formula = [](float v) -> unsigned char {
        v = std::clamp(v, 0.0f, 1.0f);
        if (!(v > 0)) return 0;
        const float s = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
        if (!(s > 0)) return 0;
        if (s >= 1) return 255;
        return static_cast<unsigned char>(s * 255.0f + 0.5f);
    };
    size_t checked = 0;
    // Every 64th float bit pattern in (0, 1]: ~16M values, all byte boundaries crossed.
    for (uint32_t bits = 1; bits <= std::bit_cast<uint32_t>(1.0f); bits += 64, ++checked) {
        const float v = std::bit_cast<float>(bits);
        ASSERT_EQ(srgbByte(v), formula(v)) << v;
    }
    // The 128 floats on each side of every boundary.
    float prev = 0;
    for (uint32_t bits = 1; bits <= std::bit_cast<uint32_t>(1.0f); bits += 4096) {
        const float v = std::bit_cast<float>(bits);
        if (formula(v) != formula(prev)) {
            for (uint32_t b = bits - 4096 > bits ? 1 : bits - 4096; b <= bits; ++b, ++checked) {
                ASSERT_EQ(srgbByte(std::bit_cast<float>(b)), formula(std::bit_cast<float>(b)));
            }
        }
        prev = v;
    }
    for (float v : {0.0f, -0.0f, -1.0f, 1.0f, 1.5f, INFINITY, -INFINITY, NAN})
        EXPECT_EQ(srgbByte(v), formula(std::isnan(v) ? 0.0f : v)) << v;
    EXPECT_GT(checked, 10000000u);
}

}  // namespace
}  // namespace sdft
