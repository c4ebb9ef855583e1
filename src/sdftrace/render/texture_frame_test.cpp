#include <gtest/gtest.h>

#include <cmath>

#include "sdftrace/render/renderer.h"
#include "test_scenes/shadow_test_scenes.h"

namespace sdft {
namespace {

// A textured object moved together with the camera and the light renders the same image: the
// textures (solid, planar and tri-planar) live in the object's frame, not the world's.
TEST(MaterialAt, TexturesMoveWithTheirObject) {
    auto scene = [](const std::string& texture, Vec3 o, float turn) {
        auto v = [&](Vec3 p) {
            std::string out = "[";
            out += std::to_string(p.x + o.x) + ", " + std::to_string(p.y + o.y) + ", ";
            out += std::to_string(p.z + o.z) + "]";
            return out;
        };
        return R"({"camera": {"eye": )" + v({0, 0.5f, 4}) + R"(, "target": )" + v({0, 0, 0}) +
               R"(, "fov": 35, "width": 48, "height": 48},
          "ambient": [0.3, 0.3, 0.3],
          "lights": [{"type": "point", "position": )" +
               v({2, 3, 4}) + R"(, "intensity": 20}],
          "materials": {"m": {"color": )" +
               texture + R"(}},
          "objects": [{"type": "box", "size": [1.4, 1.0, 0.8], "rotate": {"axis": [0, 1, 0],
                       "angle": )" +
               std::to_string(turn) + R"(}, "translate": )" + v({0, 0, 0}) +
               R"(, "material": "m"}],
          "render": {"shadows": false}})";
    };
    for (const std::string texture :
         {R"({"type": "marble", "scale": 0.3})",
          R"({"type": "checker", "scale": 0.25, "projection": "triplanar"})",
          R"({"type": "noise", "scale": 0.2, "projection": "planar", "axis": "z"})"}) {
        SCOPED_TRACE(texture);
        const testing::Rendered a = testing::renderText(scene(texture, {0, 0, 0}, 0));
        const testing::Rendered b = testing::renderText(scene(texture, {7, -3, 2}, 0));
        double diff = 0, contrast = 0;
        for (size_t i = 0; i < a.film.color.size(); ++i) {
            diff =
                std::max(diff, static_cast<double>(std::fabs(a.film.color[i] - b.film.color[i])));
            contrast = std::max(contrast, static_cast<double>(a.film.color[i]));
        }
        EXPECT_LT(diff, 0.02) << "moved";  // float rounding of the moved hit points
        EXPECT_GT(contrast, 0.2);
        // Turning the object (not the camera) changes the image: the test can see the texture.
        const testing::Rendered c = testing::renderText(scene(texture, {0, 0, 0}, 180));
        double turned = 0;
        for (size_t i = 0; i < a.film.color.size(); ++i)
            turned += std::fabs(a.film.color[i] - c.film.color[i]);
        EXPECT_GT(turned / a.film.color.size(), 0.01);
    }
}

}  // namespace
}  // namespace sdft
