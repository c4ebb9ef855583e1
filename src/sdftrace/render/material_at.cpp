#include "sdftrace/render/material_at.h"

#include <algorithm>
#include <string>

#include "sdftrace/render/direct_pixel.h"

namespace sdft {

Material materialAt(const RenderPlan& plan, Vec3 p, Vec3 n) {
    const Tape& tape = plan.tape;
    const auto& table = plan.materials;
    // One object with one untextured material (a grid file rendered directly): the blend is that
    // material with weight 1 everywhere, and the sums below would return it unchanged.
    const int only = tape.uniformMaterial();
    if (only >= 0 && only < static_cast<int>(table.size()) && table[only].colorTexture < 0)
        return table[only];
    const MaterialBlend b = tape.evalMaterial(p);
    MaterialMix mix;
    const std::string* name = nullptr;  // the heaviest weight's
    float heaviest = -1;
    MaterialBlend offset;  // the blend a step along n, once a texture needs the normal
    bool haveOffset = false;
    for (int i = 0; i < b.count; ++i) {
        const Material& src = table[std::clamp(b.id[i], 0, static_cast<int>(table.size()) - 1)];
        const float w = b.weight[i];
        Vec3 color = src.color;
        if (src.colorTexture >= 0 && src.colorTexture < static_cast<int>(plan.textures.size())) {
            const Texture& t = plan.textures[static_cast<size_t>(src.colorTexture)];
            if (textureNeedsNormal(t) && !haveOffset) {
                offset = tape.evalMaterial(p + n * textureNormalStep(p));
                haveOffset = true;
            }
            color = evalTexture(t, plan.images,
                                textureInputs(b, i, textureNeedsNormal(t) ? &offset : nullptr));
        }
        PixelMaterial mixed = pixelMaterial(src);
        mixed.color = color;
        mix.add(mixed, w);
        if (w > heaviest) {
            heaviest = w;
            name = &src.name;
        }
    }
    Material m;
    if (name) m.name = *name;
    const PixelMaterial r = mix.result();
    m.color = r.color;
    m.diffuse = r.diffuse;
    m.specular = r.specular;
    m.shininess = r.shininess;
    m.kind = r.kind;
    m.ior = r.ior;
    m.absorption = r.absorption;
    m.roughness = r.roughness;
    return m;
}

}  // namespace sdft
