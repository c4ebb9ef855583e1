// Scenes and a render helper for the shadow tests (internal to the tests).
#pragma once

#include <string>

#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"

namespace sdft::testing {

// A floor, a thick box, a thin plate on a pole and a sphere light: penumbrae of every width.
inline std::string shadowScene(const std::string& light, const std::string& render) {
    return R"({"camera": {"eye": [0.5, 3.2, 6.5], "target": [0, 0.4, 0], "fov": 40,
                          "width": 160, "height": 100},
      "ambient": [0.1, 0.1, 0.1],
      "lights": [)" +
           light + R"(],
      "objects": [
        {"type": "box", "size": [8, 0.2, 6], "translate": [0, -0.1, 0]},
        {"type": "box", "size": [0.9, 1.2, 0.9], "translate": [-1.3, 0.6, -0.4]},
        {"type": "box", "size": [1.2, 0.04, 0.8], "translate": [0.3, 1.2, -1.2]},
        {"type": "capsule", "a": [0.3, 0, -1.2], "b": [0.3, 1.18, -1.2], "radius": 0.03}],
      "render": )" +
           render + "}";
}

inline const char* kSphereLight =
    R"({"type": "sphere", "position": [-2.5, 5, 1.5], "radius": 0.5, "intensity": 30})";

struct Rendered {
    Film film;
    RenderStats stats;
};

inline Rendered renderText(const std::string& text) {
    Scene scene = parseSceneText(text, "<test>");
    Rendered r{Film(scene.camera.width, scene.camera.height), {}};
    r.stats = render(planRender(scene), r.film);
    return r;
}

}  // namespace sdft::testing
