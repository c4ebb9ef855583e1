// Fuzz target: scene files (JSON text in). Every input either describes a scene or fails with an
// InputError; a scene without assets is also prepared, planned (tape, materials, lights, camera)
// and its compiled field evaluated, so the values the parser lets through are exercised.
#include <cmath>
#include <cstdint>
#include <string>

#include "fuzz_input.h"
#include "sdftrace/core/error.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"
#include "sdftrace/scene/prepare_scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace sdft;
    fuzz::limitMemoryForFuzzing();
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        // A base directory that does not exist: asset paths stay requests and fail cleanly.
        Scene scene = describeSceneText(text, "<fuzz>", "/nonexistent-sdftrace-fuzz");
        if (!scene.assets.empty()) return 0;  // mesh, grid and bake assets: other targets
        prepareScene(scene);
        const RenderPlan plan = planRender(scene);
        const Bounds3 b = plan.tape.bounds();
        const Vec3 c = b.finite() && !b.empty() ? b.center() : Vec3(0.0f);
        for (const Vec3 p : {c, c + Vec3(0.5f, 0.25f, -0.75f), plan.camera.eye}) {
            const float f = plan.tape.eval(p);
            if (std::isnan(f)) __builtin_trap();  // a field value must never be NaN
        }
    } catch (const InputError&) {
    }
    return 0;
}
