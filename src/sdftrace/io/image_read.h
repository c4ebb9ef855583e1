// Reading images for textures: PNG, JPEG, BMP, TGA (8-bit, decoded from sRGB to linear) and
// Radiance HDR (linear) through stb_image; OpenEXR (linear, R, G, B or Y) through OpenEXR.
#pragma once

#include <string>

#include "sdftrace/render/texture.h"

namespace sdft {

// Throws InputError beginning with `what` (e.g. "scene.json: /textures/earth/file") that names the
// file and the reason: missing, unreadable, an unsupported format, or absurdly large.
TextureImage readTextureImage(const std::string& path, const std::string& what);

}  // namespace sdft
