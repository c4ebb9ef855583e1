// Scene-file textures (internal to the scene module): the top-level "textures" map and the
// textures a material's "color" may hold in place of an RGB triple (docs/scene-format.md).
#pragma once

#include <map>
#include <string>

#include "json_reader.h"
#include "sdftrace/scene/scene.h"

namespace sdft {

struct TextureContext {
    std::string baseDir;                // image paths are relative to the scene file
    std::map<std::string, int> named;   // texture name -> index in scene.textures
    std::map<std::string, int> images;  // resolved path -> index in scene.images
};

// Parses one texture object, loading its image (once per file); returns its index in
// scene.textures.
int parseTexture(const json_reader::Reader& r, const std::string& name, Scene& scene,
                 TextureContext& context);

// A material's "color": [r, g, b], a texture name, or an inline texture object. Sets `color` or
// returns the texture's index (-1 for a plain colour).
int parseColorInput(const json_reader::Reader& r, const std::string& key, Vec3& color, Scene& scene,
                    TextureContext& context);

}  // namespace sdft
