// A parsed, validated scene: the field tree, materials, lights, camera and render settings.
#pragma once

#include <string>
#include <vector>

#include "sdftrace/field/node.h"
#include "sdftrace/math/camera.h"
#include "sdftrace/render/lighting.h"
#include "sdftrace/render/render_settings.h"
#include "sdftrace/render/texture.h"

namespace sdft {

struct Scene {
    NodePtr root;
    std::vector<Material> materials;
    std::vector<Texture> textures;     // referenced by materials
    std::vector<TextureImage> images;  // decoded image files, referenced by textures
    Lighting lighting;
    CameraDesc camera;
    RenderSettings settings;
};

}  // namespace sdft
