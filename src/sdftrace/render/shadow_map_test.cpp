#include "sdftrace/render/shadow_map.h"

#include <gtest/gtest.h>

#include <cmath>

#include "test_scenes/shadow_test_scenes.h"

namespace sdft {
namespace {

using testing::renderText;
using testing::shadowScene;

// Away from shadow edges a shadow map agrees with the hard shadow ray: PCF exactly, EVSM up to
// its light bleeding. Points where the hard shadow changes within two pixels are excluded.
TEST(ShadowMaps, AgreeWithHardShadowsAwayFromEdges) {
    for (const char* light : {R"({"type": "point", "position": [-2.5, 5, 1.5], "intensity": 30})",
                              R"({"type": "directional", "direction": [0.6, -1, 0.5]})"}) {
        SCOPED_TRACE(light);
        const testing::Rendered hard =
            renderText(shadowScene(light, R"({"shadow_method": "hard"})"));
        const int w = hard.film.width, h = hard.film.height;
        const std::vector<float>& ref = hard.film.shadow;
        auto nearEdge = [&](int x, int y) {
            for (int dy = -2; dy <= 2; ++dy)
                for (int dx = -2; dx <= 2; ++dx) {
                    int xx = std::clamp(x + dx, 0, w - 1), yy = std::clamp(y + dy, 0, h - 1);
                    if (ref[yy * w + xx] != ref[y * w + x]) return true;
                }
            return false;
        };
        for (const char* method : {"pcf", "evsm"}) {
            const std::vector<float> map =
                renderText(shadowScene(light, std::string(R"({"shadow_method": ")") + method +
                                                  R"(", "shadow_map_resolution": 512})"))
                    .film.shadow;
            int checked = 0, shadowed = 0, wrong = 0;
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    if (nearEdge(x, y) || !std::isfinite(hard.film.depth[y * w + x])) continue;
                    ++checked;
                    shadowed += ref[y * w + x] == 0;
                    wrong += std::fabs(map[y * w + x] - ref[y * w + x]) > 0.25f;
                }
            EXPECT_GT(shadowed, 40) << method;
            EXPECT_LT(wrong, checked / 100) << method << ": " << wrong << " of " << checked;
        }
    }
}

// A light among the objects (inside the scene's bounds) is mapped by the cube's six faces: a point
// light between two spheres shadows neither by the other, and each casts a shadow on the floor.
TEST(ShadowMaps, CubeMapsSeeAllAroundALightAmongTheObjects) {
    const std::string objects = R"([{"type": "box", "size": [8, 0.2, 8], "translate": [0, -0.1, 0]},
        {"type": "sphere", "radius": 0.5, "translate": [-1.5, 1, 0]},
        {"type": "sphere", "radius": 0.5, "translate": [1.5, 1, 0]}])";
    auto shadow = [&](const char* method) {
        return renderText(R"({"camera": {"eye": [0, 6, 6], "target": [0, 0, 0], "width": 80,
                                         "height": 60},
                              "lights": [{"type": "point", "position": [0, 1.5, 0]}],
                              "objects": )" +
                          objects + R"(, "render": {"shadow_method": ")" + method +
                          R"(", "screen_space": false}})")
            .film.shadow;
    };
    const std::vector<float> hard = shadow("hard"), pcf = shadow("pcf");
    int shadowed = 0, differ = 0;
    for (size_t i = 0; i < hard.size(); ++i) {
        shadowed += hard[i] == 0;
        differ += std::fabs(pcf[i] - hard[i]) > 0.5f;
    }
    EXPECT_GT(shadowed, 100);
    EXPECT_LT(differ, static_cast<int>(hard.size()) / 50) << differ;
}

}  // namespace
}  // namespace sdft
