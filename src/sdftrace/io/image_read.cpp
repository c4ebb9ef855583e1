#include "sdftrace/io/image_read.h"

#include <ImfArray.h>
#include <ImfRgbaFile.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>

#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_NO_GIF
#define STBI_NO_PSD
#define STBI_NO_PIC
#define STBI_NO_PNM
#include <stb_image.h>

namespace sdft {

namespace {

constexpr int kMaxSide = 32768;
constexpr double kMaxPixels = 256.0 * 1024 * 1024;

float srgbToLinear(unsigned char c) {
    const float x = c / 255.0f;
    return x <= 0.04045f ? x / 12.92f : std::pow((x + 0.055f) / 1.055f, 2.4f);
}

void checkSize(int w, int h, const std::string& where) {
    if (w <= 0 || h <= 0 || w > kMaxSide || h > kMaxSide ||
        static_cast<double>(w) * h > kMaxPixels) {
        throw InputError(where + ": " + std::to_string(w) + " x " + std::to_string(h) +
                         " pixels; accepted: 1 to " + std::to_string(kMaxSide) +
                         " per side, at most 2^28 pixels");
    }
    // The decoded image (up to 4 floats a pixel while decoding) and its RGB floats.
    checkMemoryBudget(28.0 * w * h, where,
                      "a " + std::to_string(w) + " x " + std::to_string(h) + " texture image",
                      "use a smaller image");
}

TextureImage readExr(const std::string& path, const std::string& where) {
    TextureImage img;
    try {
        Imf::RgbaInputFile file(path.c_str());
        const Imath::Box2i dw = file.dataWindow();
        const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
        checkSize(w, h, where);
        Imf::Array2D<Imf::Rgba> pixels(h, w);
        file.setFrameBuffer(&pixels[0][0] - dw.min.x - dw.min.y * w, 1, w);
        file.readPixels(dw.min.y, dw.max.y);
        img.width = w;
        img.height = h;
        img.rgb.resize(3 * static_cast<size_t>(w) * h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const Imf::Rgba& p = pixels[y][x];
                float* out = &img.rgb[3 * (static_cast<size_t>(y) * w + x)];
                out[0] = p.r, out[1] = p.g, out[2] = p.b;
            }
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(where + ": cannot read OpenEXR image: " + e.what());
    }
    return img;
}

}  // namespace

TextureImage readTextureImage(const std::string& path, const std::string& what) {
    const std::string where = what + ": '" + path + "'";
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
        throw InputError(where + ": no such file (paths are relative to the scene file)");
    if (!std::filesystem::is_regular_file(path, ec)) throw InputError(where + ": not a file");
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    TextureImage img;
    if (ext == ".exr") {
        img = readExr(path, where);
    } else {
        int w = 0, h = 0, n = 0;
        if (!stbi_info(path.c_str(), &w, &h, &n)) {
            throw InputError(where + ": unreadable image (" + stbi_failure_reason() +
                             "); accepted: PNG, JPEG, BMP, TGA, HDR, EXR");
        }
        checkSize(w, h, where);
        img.width = w;
        img.height = h;
        const size_t count = 3 * static_cast<size_t>(w) * h;
        img.rgb.resize(count);
        if (stbi_is_hdr(path.c_str())) {
            std::unique_ptr<float, void (*)(void*)> data(stbi_loadf(path.c_str(), &w, &h, &n, 3),
                                                         stbi_image_free);
            if (!data)
                throw InputError(where + ": unreadable image (" + stbi_failure_reason() + ")");
            std::copy(data.get(), data.get() + count, img.rgb.begin());
        } else {
            std::unique_ptr<unsigned char, void (*)(void*)> data(
                stbi_load(path.c_str(), &w, &h, &n, 3), stbi_image_free);
            if (!data)
                throw InputError(where + ": unreadable image (" + stbi_failure_reason() + ")");
            for (size_t i = 0; i < count; ++i) img.rgb[i] = srgbToLinear(data.get()[i]);
        }
    }
    for (float v : img.rgb)
        if (!std::isfinite(v) || v < 0)
            throw InputError(where + ": negative or non-finite pixel values");
    img.path = path;
    return img;
}

}  // namespace sdft
