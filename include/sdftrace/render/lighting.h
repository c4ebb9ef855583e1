// Materials (Blinn-Phong) and lights of the direct-lighting integrator.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "sdftrace/core/macros.h"
#include "sdftrace/math/vec.h"

namespace sdft {

struct Material {
    // Plastic: Lambert + Blinn-Phong. Mirror: reflects, tinted by `color`. Dielectric: glass-like,
    // Fresnel-weighted reflection and refraction (Whitted 1980, Keinert et al. 2014 §4).
    enum class Kind { Plastic, Mirror, Dielectric };
    std::string name;
    Vec3 color{0.8f, 0.8f, 0.8f};  // base (diffuse) colour, linear RGB; a mirror's tint
    float diffuse = 1.0f;          // Lambert weight
    float specular = 0.2f;         // Blinn-Phong weight
    float shininess = 32.0f;       // Blinn-Phong exponent
    Kind kind = Kind::Plastic;
    float ior = 1.5f;          // dielectric: index of refraction (outside: 1)
    float roughness = -1;      // path tracer: GGX alpha; < 0: from shininess
    int colorTexture = -1;     // index into Scene::textures replacing `color`; -1: none
    Vec3 absorption{0, 0, 0};  // dielectric: Beer-Lambert coefficients per unit length
};

// Whole exponents up to this are raised by squaring (specularPower).
constexpr int kMaxSquaredExponent = 256;

// Whether specularPower raises x^e by squaring.
SDFT_HOST_DEVICE inline bool squaredExponent(float e) {
    return e >= 1 && e <= static_cast<float>(kMaxSquaredExponent) &&
           e == static_cast<float>(static_cast<int>(e));
}

// x^k for a whole k >= 1 by repeated squaring: one product order for a float and for a vector of
// floats (render/light_batch.cpp), so both give the same bits.
template <class T>
SDFT_HOST_DEVICE inline T raiseBySquaring(T x, int k) {
    T r = T{} + 1.0f, b = x;
    for (;; b *= b) {
        if (k & 1) r *= b;
        k >>= 1;
        if (k == 0) return r;
    }
}

// x^e for Blinn-Phong's specular lobe, x in [0, 1]: a whole exponent in [1, kMaxSquaredExponent]
// (the usual ones: 8, 32, 64, ...) by repeated squaring, at a fraction of powf's cost and within
// e/2 ulp of it (1e-5 relative at the largest); any other by powf.
SDFT_HOST_DEVICE inline float specularPower(float x, float e) {
    return squaredExponent(e) ? raiseBySquaring(x, static_cast<int>(e)) : std::pow(x, e);
}

// Lambert + Blinn-Phong for unit normal n, unit direction to the light l and the viewing ray's
// unit direction d, per unit of light (the CPU renderer's and render/direct_pixel.h's term).
SDFT_HOST_DEVICE inline Vec3 blinnPhong(Vec3 color, float diffuse, float specular, float shininess,
                                        Vec3 n, Vec3 l, Vec3 d) {
    const Vec3 half = normalize(l - d);
    const float spec = specularPower(std::fmax(dot(n, half), 0.0f), shininess);
    return color * (diffuse * dot(n, l)) + Vec3(specular * spec);
}

// Lights of the direct-lighting integrator. Sphere and rectangle lights have a size: their
// shadows have penumbrae (soft_shadow.h estimates them in one march, light_sample.h samples them
// for distributed shadow rays). A directional light may subtend an angle (the sun: 0.53 degrees).
struct Light {
    enum class Kind { Directional, Point, Sphere, Rect };
    Kind kind = Kind::Directional;
    Vec3 direction{-1, -1, -1};   // directional: the direction light travels (unit)
    float angle = 0;              // directional: angular diameter, radians, [0, pi/2)
    Vec3 position{0, 5, 0};       // point, sphere, rect: the centre
    float radius = 0;             // sphere: > 0
    Vec3 u{1, 0, 0}, v{0, 0, 1};  // rect: edge vectors; it emits on the side of u x v
    Vec3 color{1, 1, 1};
    // directional: irradiance scale; point, sphere: intensity (falls off as 1/d^2); rect: the
    // intensity along its normal, times the cosine off it (a Lambertian emitter).
    float intensity = 1.0f;
    bool castShadows = true;

    SDFT_HOST_DEVICE bool positional() const { return kind != Kind::Directional; }
    // Whether its shadows have a penumbra.
    SDFT_HOST_DEVICE bool hasSize() const {
        return kind == Kind::Sphere || kind == Kind::Rect ||
               (kind == Kind::Directional && angle > 0);
    }
};

struct Lighting {
    std::vector<Light> lights;
    Vec3 ambient{0.05f, 0.05f, 0.05f};
    Vec3 background{0.0f, 0.0f, 0.0f};
    // Path tracer: the radiance of the environment that rays escaping the scene see (the camera's
    // escaping rays see `background`).
    Vec3 environment{0.0f, 0.0f, 0.0f};
};

}  // namespace sdft
