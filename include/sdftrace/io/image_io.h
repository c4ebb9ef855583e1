// Image output. The format follows the extension: .png (8-bit; colour tone-mapped to sRGB, scalar
// AOVs as a false-colour heat map with a legend of their range), .exr (OpenEXR, 32-bit float),
// .pfm (portable float map). Every write is atomic (see atomic_file.h).
#pragma once

#include <string>
#include <vector>

#include "sdftrace/render/film.h"

namespace sdft {

enum class ImageFormat { Png, Exr, Pfm };

// Throws InputError naming `what` and the accepted extensions for anything else.
ImageFormat imageFormatFromPath(const std::string& path, const std::string& what);

// Float images, `channels` interleaved values per pixel, row 0 at the top.
void writeExr(const std::string& path, int width, int height, int channels,
              const std::vector<float>& data, const std::vector<std::string>& channelNames);
void writePfm(const std::string& path, int width, int height, int channels,
              const std::vector<float>& data);
void writePng(const std::string& path, int width, int height, int channels,
              const std::vector<unsigned char>& data);

// The 8-bit RGB picture a PNG of the AOV holds (not motion): colour tone-mapped to sRGB, normals
// as 0.5 n + 0.5, the others a heat map over their finite range, with its legend strip below the
// image when `legend`; `outHeight` is the picture's height.
std::vector<unsigned char> aovPicture(const Film& film, Aov aov, bool legend, int& outHeight);
// Writes one AOV of the film in the format the path asks for.
void writeAov(const Film& film, Aov aov, const std::string& path);

// 8-bit renderings used for PNG output (exposed for tests).
std::vector<unsigned char> toneMapSrgb(const std::vector<float>& linearRgb);
// One channel of it: the sRGB-encoded byte of a linear value (clamped to [0, 1]; NaN gives 0).
unsigned char srgbByte(float linear);
// Heat map of a scalar image over its finite range, with a legend strip appended at the bottom;
// returns RGB rows and sets outHeight. Non-finite pixels are drawn black.
std::vector<unsigned char> heatMapWithLegend(const std::vector<float>& values, int width,
                                             int height, const std::string& label, int& outHeight);

}  // namespace sdft
