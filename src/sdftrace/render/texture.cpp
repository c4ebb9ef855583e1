#include "sdftrace/render/texture.h"

namespace sdft {

Vec3 evalTexture(const TextureParams& t, const std::vector<TextureImage>& images,
                 const TextureInputs& in) {
    // The one image a texture reads, as a table of its index's length.
    ImageView view[1];
    ImageTable table;
    if (t.kind == TextureParams::Kind::Image && t.image >= 0 &&
        t.image < static_cast<int>(images.size())) {
        TextureParams one = t;
        one.image = 0;
        view[0] = images[static_cast<size_t>(t.image)].view();
        table = {view, 1};
        return evalTexture(one, table, in);
    }
    return evalTexture(t, table, in);
}

const char* textureKindNames() { return "checker, noise, turbulence, marble, wood, image"; }

bool parseTextureKind(const std::string& s, Texture::Kind& out) {
    using K = Texture::Kind;
    if (s == "checker") return out = K::Checker, true;
    if (s == "noise") return out = K::Noise, true;
    if (s == "turbulence") return out = K::Turbulence, true;
    if (s == "marble") return out = K::Marble, true;
    if (s == "wood") return out = K::Wood, true;
    if (s == "image") return out = K::Image, true;
    return false;
}

const char* textureProjectionNames() { return "solid, planar, triplanar, grid"; }

bool parseTextureProjection(const std::string& s, Texture::Projection& out) {
    using P = Texture::Projection;
    if (s == "solid") return out = P::Solid, true;
    if (s == "planar") return out = P::Planar, true;
    if (s == "triplanar") return out = P::Triplanar, true;
    if (s == "grid") return out = P::Grid, true;
    return false;
}

}  // namespace sdft
