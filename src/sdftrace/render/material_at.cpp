#include "sdftrace/render/material_at.h"

#include <algorithm>

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
    Material m;
    m.color = Vec3(0.0f);
    m.diffuse = m.specular = m.shininess = 0;
    m.absorption = Vec3(0.0f);
    m.ior = 0;
    m.roughness = 0;
    float heaviest = -1, roughWeight = 0;
    MaterialBlend offset;  // the blend a step along n: the object frame's normal
    bool haveOffset = false;
    for (int i = 0; i < b.count; ++i) {
        const Material& src = table[std::clamp(b.id[i], 0, static_cast<int>(table.size()) - 1)];
        const float w = b.weight[i];
        Vec3 color = src.color;
        if (src.colorTexture >= 0 && src.colorTexture < static_cast<int>(plan.textures.size())) {
            const Texture& t = plan.textures[static_cast<size_t>(src.colorTexture)];
            TextureInputs in;
            in.point = b.local[i];
            in.hasUv = b.hasUv[i];
            in.u = b.u[i];
            in.v = b.v[i];
            if (t.projection != Texture::Projection::Solid || t.kind == Texture::Kind::Image) {
                // The normal in the object's frame: where its frame maps a small step along n.
                // Exact under rotation and uniform scale; a non-uniform scale tilts it toward
                // the squashed axis (only the projection's blend weights see that).
                const float h = 1e-3f * std::max(1.0f, length(p));
                if (!haveOffset) offset = tape.evalMaterial(p + n * h);
                haveOffset = true;
                in.normal = Vec3(0, 1, 0);
                for (int j = 0; j < offset.count; ++j)
                    if (offset.id[j] == b.id[i] && length(offset.local[j] - b.local[i]) > 0)
                        in.normal = normalize(offset.local[j] - b.local[i]);
            }
            color = evalTexture(t, plan.images, in);
        }
        m.color += color * w;
        m.diffuse += src.diffuse * w;
        m.specular += src.specular * w;
        m.shininess += src.shininess * w;
        m.ior += src.ior * w;
        m.absorption += src.absorption * w;
        if (src.roughness >= 0) {
            m.roughness += src.roughness * w;
            roughWeight += w;
        }
        if (w > heaviest) {
            heaviest = w;
            m.kind = src.kind;
            m.name = src.name;
        }
    }
    m.roughness = roughWeight > 0 ? m.roughness / roughWeight : -1;
    return m;
}

}  // namespace sdft
