// Materials (Blinn-Phong) and lights of the direct-lighting integrator.
#pragma once

#include <string>
#include <vector>

#include "sdftrace/math/vec.h"

namespace sdft {

struct Material {
    std::string name;
    Vec3 color{0.8f, 0.8f, 0.8f};  // base (diffuse) colour, linear RGB
    float diffuse = 1.0f;          // Lambert weight
    float specular = 0.2f;         // Blinn-Phong weight
    float shininess = 32.0f;       // Blinn-Phong exponent
};

struct Light {
    enum class Kind { Directional, Point };
    Kind kind = Kind::Directional;
    Vec3 direction{-1, -1, -1};  // directional: the direction light travels
    Vec3 position{0, 5, 0};      // point
    Vec3 color{1, 1, 1};
    float intensity = 1.0f;  // directional: irradiance scale; point: intensity (falls off as 1/d^2)
    bool castShadows = true;
};

struct Lighting {
    std::vector<Light> lights;
    Vec3 ambient{0.05f, 0.05f, 0.05f};
    Vec3 background{0.0f, 0.0f, 0.0f};
};

}  // namespace sdft
