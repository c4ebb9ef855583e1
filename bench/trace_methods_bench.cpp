// Keinert et al. 2014 §3.1-3.2 measured: classic sphere tracing vs over-relaxation vs
// over-relaxation + screen-space selection, and the same with Bálint & Valasek's adaptive factor
// instead of the fixed one (decision 22), and Galin et al.'s segment tracing (decision 23), on
// several scenes, primary rays only, all in one run.
//
// Counters per benchmark: evals/ray (field evaluations per primary ray, hardware-independent),
// items_per_second (rays/s), hit_diff_% (share of pixels whose hit/miss differs from classic),
// depth_diff_% (share of pixels hit by both whose depth differs by more than 5% from classic, i.e.
// another surface; the screen-space criterion legitimately moves grazing hits by a pixel footprint
// over cos(theta), several percent of t on a distant floor), exhausted_% (share of rays that gave
// up after max_steps evaluations without converging: grazing rays, mostly near the horizon).
//
//   build/release/bench/sdftrace_bench --benchmark_filter=Methods --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true   (one command line)
#include <benchmark/benchmark.h>

#include <map>
#include <string>

#include "sdftrace/field/tape.h"
#include "sdftrace/math/camera.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/trace/field_tracer.h"

namespace sdft {
namespace {

constexpr int kWidth = 320, kHeight = 240;

struct Prepared {
    Scene scene;
    Tape tape;           // with bounds culling (decision 0002), as the renderer uses it
    Tape tapeNoCulling;  // the same field without it
    std::vector<RaySegment> rays;
};

const Prepared& prepared(const std::string& name) {
    static std::map<std::string, Prepared> cache;
    auto it = cache.find(name);
    if (it != cache.end()) return it->second;
    Prepared p;
    p.scene = parseSceneFile(std::string(SDFT_SOURCE_DIR) + "/examples/" + name + ".json");
    p.scene.camera.width = kWidth;
    p.scene.camera.height = kHeight;
    p.tape = compileTape(p.scene.root);
    p.tapeNoCulling = compileTape(p.scene.root, {.boundsCulling = false});
    Camera cam(p.scene.camera);
    // Tile order (16x16), as the renderer traces them.
    for (int ty = 0; ty < kHeight; ty += 16)
        for (int tx = 0; tx < kWidth; tx += 16)
            for (int y = ty; y < ty + 16; ++y)
                for (int x = tx; x < tx + 16; ++x)
                    p.rays.push_back({cam.pixelRay(x, y), 0, p.scene.settings.maxDistance});
    return cache.emplace(name, std::move(p)).first->second;
}

enum Method {
    kClassic,
    kRelaxed,
    kRelaxedScreenSpace,
    kEnhanced,
    kEnhancedNoCulling,
    kAdaptive,
    kAdaptiveScreenSpace,
    kAdaptiveEnhanced,
    kSegment,
    kSegmentScreenSpace,
    kSegmentEnhanced
};

TraceOptions options(Method m, const Prepared& p) {
    TraceOptions o = TraceOptions::classic();
    o.pixelRadius = Camera(p.scene.camera).pixelRadius();
    o.rootIters = 0;      // the papers' methods; the root refinement is measured in exact_hits_test
    if (m >= kSegment) {  // Galin et al.'s segment tracing instead of any over-relaxation
        o.segmentTracing = true;
        o.screenSpace = m >= kSegmentScreenSpace;
        if (m == kSegmentEnhanced) o.discontinuityIters = 3;
        return o;
    }
    if (m >= kAdaptive) {  // Bálint & Valasek's adaptive factor instead of Keinert's fixed one
        o.adaptiveRelaxation = true;
        o.screenSpace = m >= kAdaptiveScreenSpace;
        if (m == kAdaptiveEnhanced) o.discontinuityIters = 3;
        return o;
    }
    if (m >= kRelaxed) o.omega = 1.2f;
    if (m >= kRelaxedScreenSpace) o.screenSpace = true;
    if (m >= kEnhanced) o.discontinuityIters = 3;
    return o;
}

std::vector<TraceResult> traceAll(const Prepared& p, const TraceOptions& o, bool culling = true) {
    const Tape& tape = culling ? p.tape : p.tapeNoCulling;
    std::vector<TraceResult> results(p.rays.size());
    PacketScratch scratch;
    for (size_t start = 0; start < p.rays.size(); start += 256) {
        size_t n = std::min<size_t>(256, p.rays.size() - start);
        tracePacket(tape, std::span(p.rays).subspan(start, n), o,
                    std::span(results).subspan(start, n), scratch);
    }
    return results;
}

const std::vector<TraceResult>& classicResults(const std::string& name) {
    static std::map<std::string, std::vector<TraceResult>> cache;
    auto it = cache.find(name);
    if (it == cache.end()) {
        const Prepared& p = prepared(name);
        it = cache.emplace(name, traceAll(p, options(kClassic, p))).first;
    }
    return it->second;
}

void Methods(benchmark::State& state, std::string scene, Method method) {
    const Prepared& p = prepared(scene);
    TraceOptions o = options(method, p);
    std::vector<TraceResult> results;
    for (auto _ : state) {
        results = traceAll(p, o, method != kEnhancedNoCulling);
        benchmark::DoNotOptimize(results.data());
    }
    const auto& ref = classicResults(scene);
    double evals = 0, hitDiff = 0, depthDiff = 0, exhausted = 0;
    for (size_t i = 0; i < results.size(); ++i) {
        evals += results[i].evaluations;
        if (!results[i].hit && results[i].evaluations >= o.maxSteps) exhausted += 1;
        if (results[i].hit != ref[i].hit)
            hitDiff += 1;
        else if (results[i].hit && std::fabs(results[i].t - ref[i].t) > 0.05 * ref[i].t)
            depthDiff += 1;
    }
    double n = static_cast<double>(results.size());
    state.counters["evals/ray"] = evals / n;
    state.counters["hit_diff_%"] = 100 * hitDiff / n;
    state.counters["depth_diff_%"] = 100 * depthDiff / n;
    state.counters["exhausted_%"] = 100 * exhausted / n;  // missed after max_steps (grazing rays)
    state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * results.size()));
}

void registerAll() {
    for (const char* scene : {"many_blend", "thin", "jewel", "city", "demo"}) {
        for (auto [name, m] : {std::pair{"classic", kClassic},
                               {"relaxed", kRelaxed},
                               {"relaxed+screen", kRelaxedScreenSpace},
                               {"enhanced", kEnhanced},
                               {"enhanced-no-culling", kEnhancedNoCulling},
                               {"adaptive", kAdaptive},
                               {"adaptive+screen", kAdaptiveScreenSpace},
                               {"adaptive-enhanced", kAdaptiveEnhanced},
                               {"segment", kSegment},
                               {"segment+screen", kSegmentScreenSpace},
                               {"segment-enhanced", kSegmentEnhanced}}) {
            benchmark::RegisterBenchmark((std::string("Methods/") + scene + "/" + name).c_str(),
                                         Methods, std::string(scene), m)
                ->Unit(benchmark::kMillisecond)
                ->MinTime(0.3);
        }
    }
}

}  // namespace
}  // namespace sdft

int main(int argc, char** argv) {
    sdft::registerAll();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
