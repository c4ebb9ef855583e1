#include "sdftrace/io/image_read.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "sdftrace/core/error.h"
#include "sdftrace/io/image_io.h"

namespace sdft {
namespace {

std::string tempName(const std::string& name) {
    return (std::filesystem::temp_directory_path() /
            ("sdftrace-read-" + std::to_string(::getpid()) + "-" + name))
        .string();
}

// PNG is 8-bit sRGB: reading decodes to linear, so 8-bit value c reads as srgb^-1(c / 255).
TEST(ImageRead, PngDecodesSrgbToLinear) {
    const std::string path = tempName("ramp.png");
    std::vector<unsigned char> px;
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 3; ++x)
            px.insert(px.end(), {static_cast<unsigned char>(x * 100),
                                 static_cast<unsigned char>(y * 255), 7});
    writePng(path, 3, 2, 3, px);
    const TextureImage img = readTextureImage(path, "test");
    ASSERT_EQ(img.width, 3);
    ASSERT_EQ(img.height, 2);
    auto linear = [](float c) {
        c /= 255;
        return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
    };
    for (size_t i = 0; i < px.size(); ++i) EXPECT_NEAR(img.rgb[i], linear(px[i]), 1e-6f) << i;
    std::filesystem::remove(path);
}

TEST(ImageRead, ExrKeepsLinearFloats) {
    const std::string path = tempName("float.exr");
    std::vector<float> px = {0.0f, 0.5f, 2.0f, 10.0f, 0.25f, 0.125f};
    writeExr(path, 2, 1, 3, px, {"R", "G", "B"});
    const TextureImage img = readTextureImage(path, "test");
    ASSERT_EQ(img.width, 2);
    for (size_t i = 0; i < px.size(); ++i) EXPECT_NEAR(img.rgb[i], px[i], 1e-2f * px[i]);  // half
    std::filesystem::remove(path);
}

void expectError(const std::string& path, const std::string& fragment) {
    try {
        readTextureImage(path, "scene.json: /textures/t/file");
        ADD_FAILURE() << "accepted " << path;
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("scene.json: /textures/t/file"), std::string::npos) << what;
        EXPECT_NE(what.find(path), std::string::npos) << what;
        EXPECT_NE(what.find(fragment), std::string::npos) << what;
    }
}

TEST(ImageRead, MissingAndUnreadableFilesAreClearErrors) {
    expectError(tempName("missing.png"), "no such file");
    const std::string garbage = tempName("garbage.png");
    std::ofstream(garbage) << "this is not an image";
    expectError(garbage, "unreadable image");
    std::filesystem::remove(garbage);
    expectError(std::filesystem::temp_directory_path().string(), "not a file");
}

}  // namespace
}  // namespace sdft
