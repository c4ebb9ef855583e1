// Uses sdftrace's public API from an installed tree: parse a scene, evaluate its field, render it
// to a PNG. Exits non-zero if anything is off.
#include <cmath>
#include <cstdio>
#include <string>

#include "sdftrace/core/build_info.h"
#include "sdftrace/core/error.h"
#include "sdftrace/io/image_io.h"
#include "sdftrace/render/film.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"
#include "sdftrace/scene/prepare_scene.h"

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: consumer OUT.png\n");
        return 2;
    }
    const std::string json = R"({
      "camera": {"eye": [0, 1, 4], "target": [0, 0.5, 0], "width": 96, "height": 64},
      "lights": [{"type": "directional", "direction": [-1, -2, -1]}],
      "objects": [
        {"type": "sphere", "radius": 0.5, "translate": [0, 0.5, 0]},
        {"type": "plane", "normal": [0, 1, 0], "distance": 0}
      ]
    })";
    try {
        sdft::Scene scene = sdft::parseSceneText(json, "consumer.json");
        sdft::prepareScene(scene);
        const sdft::RenderPlan plan = sdft::planRender(scene);
        sdft::Film film(plan.camera.width, plan.camera.height);
        const sdft::RenderStats stats = sdft::render(plan, film);
        int sphere = 0;
        for (float d : film.depth) sphere += std::isfinite(d) && d < 3.9f;
        sdft::writeAov(film, sdft::Aov::Color, argv[1]);
        std::printf("sdftrace %s: %llu rays, %llu hits, %d on the sphere\n",
                    sdft::buildInfo().version, static_cast<unsigned long long>(stats.primaryRays),
                    static_cast<unsigned long long>(stats.hits), sphere);
        if (stats.primaryRays != 96u * 64u || stats.hits == 0 || sphere < 100) return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "consumer: %s\n", e.what());
        return 1;
    }
    return 0;
}
