// The path tracer's per-pixel material table (the GPU's lookup) against the CPU's full materials:
// on untextured scenes the same materials, hence the same paths bit for bit (pathRadiance is the
// CPU path tracer's own function; path_tracer_test.cpp holds it to the direct integrator and to
// energy conservation).
#include "sdftrace/render/path_pixel.h"

#include <gtest/gtest.h>

#include <string>

#include "sdftrace/render/render_plan.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"

namespace sdft {
namespace {

// Paths with the table's materials against render()'s film: the colours and the counters.
void tableMaterialsTraceTheCpusPaths(const RenderPlan& plan) {
    const int w = plan.camera.width, h = plan.camera.height;
    FrameView frame;
    frame.camera = plan.camera;
    frame.frame = 3;  // a later frame: other random streams
    Film film(w, h);
    const RenderStats stats = render(plan, frame, film, false);
    const DirectPixelTables tables = directPixelTables(plan);
    const PathPixelView view = pathPixelView(plan, frame, tables);
    const auto table = [&](Vec3 p, Vec3 n) {
        return direct_pixel::materialAt<kTapeMaxScalarRegs>(view.direct, p, n);
    };
    PathCounters c;
    int hits = 0;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            Vec3 sum(0.0f);
            float depth = INFINITY;
            for (int k = 0; k < view.samplesPerPixel; ++k)
                sum += pathRadiance(view, table, x, y, k, c, k == 0 ? &depth : nullptr, nullptr,
                                    nullptr);
            const Vec3 color = sum / static_cast<float>(view.samplesPerPixel);
            for (int a = 0; a < 3; ++a) ASSERT_EQ(color[a], film.color[3 * i + a]) << x << "," << y;
            ASSERT_EQ(depth, film.depth[i]) << x << "," << y;
            hits += std::isfinite(depth);
        }
    }
    EXPECT_GT(hits, w * h / 10);
    EXPECT_EQ(c.primaryRays, stats.primaryRays);
    EXPECT_EQ(c.primaryEvaluations, stats.primaryEvaluations);
    EXPECT_EQ(c.secondaryRays, stats.secondaryRays);
    EXPECT_EQ(c.shadowRays, stats.shadowRays);
    EXPECT_EQ(c.shadowEvaluations, stats.shadowEvaluations);
}

// The path example (mirror, glass, plastic of several roughnesses), glass_shapes and the demo
// path traced, blended materials (many_blend) and textures (procedural, image, grid (u, v)).
TEST(PathPixel, TableMaterialsTraceTheCpusPaths) {
    for (const char* name :
         {"path", "glass_shapes", "demo", "many_blend", "textures", "projected"}) {
        SCOPED_TRACE(name);
        Scene scene = parseSceneFile(std::string(SDFT_SOURCE_DIR) + "/examples/" + name + ".json");
        scene.camera.width = 32;
        scene.camera.height = 18;
        scene.settings.threads = 1;
        scene.settings.pathTracing = true;
        scene.settings.samplesPerPixel = 2;
        const RenderPlan plan = planRender(scene);
        ASSERT_EQ(directPixelUnsupported(plan), "");
        tableMaterialsTraceTheCpusPaths(plan);
    }
}

}  // namespace
}  // namespace sdft
