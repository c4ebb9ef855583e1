#include "parse_texture.h"

#include <filesystem>

#include "sdftrace/io/image_read.h"

namespace sdft {

using json_reader::Reader;

namespace {

const auto nonNegative = [](double v) { return v >= 0 && v < 1e30; };
const auto positive = [](double v) { return v > 0 && v < 1e30; };

}  // namespace

int parseTexture(const Reader& r, const std::string& name, Scene& scene, TextureContext& ctx) {
    r.requireObject("a texture");
    r.allowKeys({"type", "projection", "colors", "scale", "octaves", "gain", "strength", "axis",
                 "sharpness", "file"});
    Texture t;
    t.name = name;
    const std::string type = r.string("type");
    if (!parseTextureKind(type, t.kind))
        r.failKey("type", "unknown texture type '" + type + "'; accepted: " + textureKindNames());
    const bool image = t.kind == Texture::Kind::Image;
    t.projection = image ? Texture::Projection::Triplanar : Texture::Projection::Solid;
    if (r.has("projection")) {
        const std::string p = r.string("projection");
        if (!parseTextureProjection(p, t.projection)) {
            r.failKey("projection",
                      "unknown projection '" + p + "'; accepted: " + textureProjectionNames());
        }
        if (image && t.projection == Texture::Projection::Solid) {
            r.failKey("projection",
                      "an image has no third dimension; accepted for images: planar, triplanar, "
                      "grid");
        }
    }
    if (r.has("colors")) {
        if (image) r.failKey("colors", "not used by image textures");
        const Reader c = r.child("colors");
        c.requireArray("two colours [[r, g, b], [r, g, b]]");
        if (c.value().size() != 2) c.fail("expected two colours [[r, g, b], [r, g, b]]");
        for (int i = 0; i < 2; ++i) {
            const Reader e = c.element(static_cast<size_t>(i));
            if (!e.value().is_array() || e.value().size() != 3)
                e.fail("expected a colour [r, g, b]");
            Vec3 v;
            for (int k = 0; k < 3; ++k) {
                const auto& x = e.value().at(static_cast<size_t>(k));
                if (!x.is_number() || !nonNegative(x.get<double>()))
                    e.fail("expected non-negative linear RGB");
                v[k] = x.get<float>();
            }
            t.colors[i] = v;
        }
    }
    t.scale = r.number("scale", t.scale, positive, "a positive length (scene units per unit)");
    t.octaves = r.integer("octaves", t.octaves, 1, 16);
    t.gain = r.number(
        "gain", t.gain, [](double v) { return v > 0 && v < 1; }, "an octave gain in (0, 1)");
    t.strength = r.number("strength", t.strength, nonNegative, "a non-negative weight");
    t.sharpness = r.number(
        "sharpness", t.sharpness, [](double v) { return v >= 1 && v <= 64; },
        "a blend exponent in [1, 64]");
    if (r.has("axis")) {
        const std::string a = r.string("axis");
        if (a != "x" && a != "y" && a != "z") r.failKey("axis", "expected x, y or z");
        t.axis = a[0] - 'x';
    }
    if (image) {
        if (!r.has("file")) r.fail("missing required key 'file' (the image of an image texture)");
        std::filesystem::path path(r.string("file"));
        if (path.is_relative() && !ctx.baseDir.empty()) path = ctx.baseDir / path;
        const std::string key = path.lexically_normal().string();
        auto it = ctx.images.find(key);
        if (it == ctx.images.end()) {
            scene.images.push_back(readTextureImage(key, r.source() + ": " + r.path() + "/file"));
            it = ctx.images.emplace(key, static_cast<int>(scene.images.size()) - 1).first;
        }
        t.image = it->second;
    } else if (r.has("file")) {
        r.failKey("file", "only image textures read a file");
    }
    scene.textures.push_back(t);
    return static_cast<int>(scene.textures.size()) - 1;
}

int parseColorInput(const Reader& r, const std::string& key, Vec3& color, Scene& scene,
                    TextureContext& ctx) {
    if (!r.has(key)) return -1;
    const auto& v = r.value().at(key);
    if (v.is_string()) {
        const std::string name = v.get<std::string>();
        auto it = ctx.named.find(name);
        if (it == ctx.named.end()) {
            std::string known;
            for (const auto& [k, i] : ctx.named) known += (known.empty() ? "" : ", ") + k;
            r.failKey(key, "unknown texture '" + name +
                               "'; defined in /textures: " + (known.empty() ? "none" : known));
        }
        return it->second;
    }
    if (v.is_object()) return parseTexture(r.child(key), "", scene, ctx);
    color = r.vec3(key, color, nonNegative,
                   "non-negative linear RGB, a texture name or a texture object");
    return -1;
}

}  // namespace sdft
