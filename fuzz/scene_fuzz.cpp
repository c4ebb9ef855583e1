// Fuzz target: scene files (JSON text in, keyframes included). Every input either describes a
// scene or fails with an InputError; a scene without assets is also prepared, planned (tape,
// materials, lights, camera) and its compiled field evaluated, at its start and, when animated,
// between keys and at its end, so the values the parser lets through are exercised.
#include <cmath>
#include <cstdint>
#include <string>

#include "fuzz_input.h"
#include "sdftrace/core/error.h"
#include "sdftrace/scene/animated_scene.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"
#include "sdftrace/scene/prepare_scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace sdft;
    fuzz::limitMemoryForFuzzing();
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        // A base directory that does not exist: asset paths stay requests and fail cleanly. The
        // keyframes are checked at every key as the file is read (AnimatedScene); the scene is
        // then described at its start and between keys, as `render --time` and animations do.
        const AnimatedScene animated =
            AnimatedScene::fromText(text, "<fuzz>", "/nonexistent-sdftrace-fuzz");
        const SceneTime& time = animated.time();
        const int instants = time.animated ? 3 : 1;
        for (int i = 0; i < instants; ++i) {
            const double t = time.start + (time.end - time.start) * (i == 0   ? 0.0
                                                                     : i == 1 ? 0.37
                                                                              : 1.0);
            Scene scene = animated.describeAt(t);
            if (!scene.assets.empty()) return 0;  // mesh, grid and bake assets: other targets
            prepareScene(scene);
            const RenderPlan plan = planRender(scene);
            const Bounds3 b = plan.tape.bounds();
            const Vec3 c = b.finite() && !b.empty() ? b.center() : Vec3(0.0f);
            for (const Vec3 p : {c, c + Vec3(0.5f, 0.25f, -0.75f), plan.camera.eye}) {
                const float f = plan.tape.eval(p);
                if (std::isnan(f)) __builtin_trap();  // a field value must never be NaN
            }
        }
    } catch (const InputError&) {
    }
    return 0;
}
