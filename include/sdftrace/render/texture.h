// Textures as material inputs (Liktor 2008, §4.2 and §5.5). An implicit surface has no vertices
// to carry (u, v), so a colour comes from
//  - a solid (3D) procedural texture at the point (§4.2.1, §5.5.1): checker, Perlin noise with
//    octaves, turbulence, marble, wood;
//  - a 2D texture (an image, or a procedural one on the plane) projected onto the surface
//    (§4.2.2): planar along an axis, tri-planar blended by the normal, or through texture
//    coordinates precomputed into a grid by tracing particles along the gradient to a helper
//    surface (§5.5.2; bake/texture_coords.h).
// Points and normals are in the frame of the object that carries the material (inside its own
// translate, rotate and scale), so textures move with their objects.
#pragma once

#include <string>
#include <vector>

#include "sdftrace/math/vec.h"

namespace sdft {

// A decoded image: linear RGB, rows top to bottom.
struct TextureImage {
    std::string path;
    int width = 0, height = 0;
    std::vector<float> rgb;
    // Bilinear, repeating; v = 0 is the bottom row, v = 1 the top.
    Vec3 sample(float u, float v) const;
};

struct Texture {
    enum class Kind { Checker, Noise, Turbulence, Marble, Wood, Image };
    enum class Projection {
        Solid,      // procedural at the 3D point
        Planar,     // along `axis` (0 x, 1 y, 2 z): the other two coordinates
        Triplanar,  // the three planar projections weighted by |n_axis|^sharpness
        Grid,       // (u, v) stored in the object's grid (Liktor §5.5.2); tri-planar elsewhere
    };
    std::string name;
    Kind kind = Kind::Checker;
    Projection projection = Projection::Solid;
    Vec3 colors[2] = {Vec3(0.1f), Vec3(0.9f)};  // procedural: the two ends of the pattern
    float scale = 1;      // scene units per pattern unit (per image repeat); grid: (u, v) units
    int octaves = 4;      // noise, turbulence, marble, wood
    float gain = 0.5f;    // amplitude ratio of successive octaves (frequency doubles)
    float strength = 1;   // marble and wood: weight of the turbulence that bends the pattern
    int axis = 1;         // planar projection, marble's stripes and wood's rings
    float sharpness = 4;  // tri-planar blend exponent
    int image = -1;       // index into the scene's images
};

// What a texture is looked up with.
struct TextureInputs {
    Vec3 point;   // in the material's object frame
    Vec3 normal;  // unit, same frame
    bool hasUv = false;
    float u = 0, v = 0;  // from a texture-coordinate grid
};

// The scalar pattern of a procedural texture in [0, 1] at q (already divided by the scale).
float proceduralPattern(const Texture& t, Vec3 q);

Vec3 evalTexture(const Texture& t, const std::vector<TextureImage>& images,
                 const TextureInputs& in);

// Names as in scene files.
const char* textureKindNames();  // "checker, noise, turbulence, marble, wood, image"
bool parseTextureKind(const std::string& s, Texture::Kind& out);
const char* textureProjectionNames();  // "solid, planar, triplanar, grid"
bool parseTextureProjection(const std::string& s, Texture::Projection& out);

}  // namespace sdft
