// Scenes of many primitives with hierarchical Lipschitz pruning on and off (field/tape_prune.h,
// decision 21), all in one run: four generated scene kinds at N = 64 ... 65,536 primitives,
// 640x360, no shadows. Per row: JSON parse time, the pruned cells' build time, evaluations per
// pixel (primary rays, normals), render time, time per evaluation (render wall time / every
// evaluation), and the pixels whose depth differs from the unpruned render's by more than 1e-4 t.
//
// Each scene from three cameras (above, close among the objects, grazing the ground); at the end,
// the JSON parse alone of scenes of --parse primitives. With --build-only 1, the pruned cells'
// build alone, per scene kind and N. --tracer picks the primary rays' tracer: the renderer's
// default, --classic's plain sphere tracing, or segment tracing (decision 23).
//
//   build/release/bench/sdftrace_pruning_bench [--reps 3] [--threads 2] [--max 65536]
//       [--max-off 16384] [--kinds clusters,city,molecule,sculpt] [--views above,close,grazing]
//       [--parse 100000] [--build-only 1] [--tracer default|classic|segment]
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "bench_flags.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/render/film.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"

namespace sdft {
namespace {

using Clock = std::chrono::steady_clock;
constexpr int kWidth = 640, kHeight = 360;

double ms(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
}

std::string v3(float x, float y, float z) {
    char b[96];
    std::snprintf(b, sizeof b, "[%.4f, %.4f, %.4f]", x, y, z);
    return b;
}

// The primitives spread over a square of side `side` (about 1.2 units per cluster of 8).
float sideFor(int n) { return 1.2f * std::sqrt(std::max(1.0f, n / 8.0f)); }

// Clusters of eight spheres and boxes blended by smooth_union, the clusters in one union.
std::string clusters(int n, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1, 1);
    const int per = 8, count = std::max(1, n / per),
              grid = static_cast<int>(std::ceil(std::sqrt(count)));
    std::ostringstream s;
    for (int c = 0; c < count; ++c) {
        const float cx = (c % grid - 0.5f * (grid - 1)) * 1.2f,
                    cz = (c / grid - 0.5f * (grid - 1)) * 1.2f;
        s << (c ? ",\n" : "") << R"({"type": "smooth_union", "k": 0.15, "children": [)";
        for (int i = 0; i < per; ++i) {
            const float x = cx + 0.3f * u(rng), y = 0.35f + 0.25f * u(rng), z = cz + 0.3f * u(rng);
            s << (i ? ", " : "");
            if (i % 2)
                s << R"({"type": "sphere", "radius": 0.16, "translate": )" << v3(x, y, z) << "}";
            else
                s << R"({"type": "box", "size": [0.24, 0.24, 0.24], "translate": )" << v3(x, y, z)
                  << "}";
        }
        s << "]}";
    }
    return s.str();
}

// Buildings (boxes) with three windows each cut out by a difference.
std::string city(int n, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0, 1);
    const int count = std::max(1, n / 4), grid = static_cast<int>(std::ceil(std::sqrt(count)));
    std::ostringstream s;
    for (int b = 0; b < count; ++b) {
        const float x = (b % grid - 0.5f * (grid - 1)) * 0.6f,
                    z = (b / grid - 0.5f * (grid - 1)) * 0.6f;
        const float h = 0.3f + 0.9f * u(rng);
        s << (b ? ",\n" : "") << R"({"type": "difference", "children": [)"
          << R"({"type": "box", "size": [0.4, )" << h << R"(, 0.4], "translate": )"
          << v3(x, 0.5f * h, z) << "}";
        for (int w = 0; w < 3; ++w)
            s << R"(, {"type": "box", "size": [0.12, 0.1, 0.5], "translate": )"
              << v3(x - 0.12f + 0.12f * w, h * (0.25f + 0.5f * u(rng)), z) << "}";
        s << "]}";
    }
    return s.str();
}

// Atoms along a random walk folded into a slab, in one union.
std::string molecule(int n, std::mt19937& rng) {
    std::normal_distribution<float> g(0, 1);
    const float side = sideFor(n);
    std::ostringstream s;
    float x = 0, y = 0.5f, z = 0;
    for (int i = 0; i < n; ++i) {
        Vec3 d(g(rng), g(rng), g(rng));
        d = normalize(d) * 0.14f;
        x = std::clamp(x + d.x, -0.5f * side, 0.5f * side);
        y = std::clamp(y + d.y, 0.2f, 1.0f);
        z = std::clamp(z + d.z, -0.5f * side, 0.5f * side);
        s << (i ? ",\n" : "") << R"({"type": "sphere", "radius": )" << (i % 3 ? 0.09 : 0.12)
          << R"(, "translate": )" << v3(x, y, z) << "}";
    }
    return s.str();
}

// Strokes of 16 capsules blended along their path, the strokes in one union.
std::string sculpt(int n, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1, 1);
    const float side = sideFor(n);
    const int per = 16, count = std::max(1, n / per);
    std::ostringstream s;
    for (int c = 0; c < count; ++c) {
        Vec3 p(0.5f * side * u(rng), 0.3f + 0.2f * u(rng), 0.5f * side * u(rng));
        Vec3 dir = normalize(Vec3(u(rng), 0.3f * u(rng), u(rng)));
        s << (c ? ",\n" : "") << R"({"type": "smooth_union", "k": 0.06, "children": [)";
        for (int i = 0; i < per; ++i) {
            dir = normalize(dir + Vec3(0.4f * u(rng), 0.2f * u(rng), 0.4f * u(rng)));
            const Vec3 q = p + dir * 0.08f;
            s << (i ? ", " : "") << R"({"type": "capsule", "a": )" << v3(p.x, p.y, p.z)
              << R"(, "b": )" << v3(q.x, q.y, q.z) << R"(, "radius": 0.035})";
            p = q;
        }
        s << "]}";
    }
    return s.str();
}

// The camera: from above at 30-40 degrees over the whole scene, close among the objects, or
// grazing the ground plane from its edge.
std::string cameraJson(const std::string& view, int n) {
    const float side = sideFor(n);
    Vec3 eye(0.0f, 0.45f * side + 1.5f, 0.75f * side + 1.5f), target(0, 0.3f, 0);
    if (view == "close") {
        eye = Vec3(0.1f * side + 0.5f, 1.6f, 0.1f * side + 1.5f);
        target = Vec3(0.1f * side - 0.5f, 0.2f, 0.1f * side - 1.0f);
    } else if (view == "grazing") {
        eye = Vec3(-0.1f * side, 0.25f, 0.55f * side + 1.0f);
        target = Vec3(0.1f * side, 0.3f, -0.5f * side);
    }
    return R"({"eye": )" + v3(eye.x, eye.y, eye.z) + R"(, "target": )" +
           v3(target.x, target.y, target.z) + R"(, "fov": 45, "width": )" + std::to_string(kWidth) +
           R"(, "height": )" + std::to_string(kHeight) + "}";
}

std::string sceneText(const std::string& objects, int n, const std::string& view) {
    std::ostringstream s;
    s << R"({"camera": )" << cameraJson(view, n) << ",\n"
      << R"("render": {"shadows": false},)"
      << R"("lights": [{"type": "directional", "direction": [0.4, -1, -0.5], "intensity": 1}],)"
      << R"("objects": [{"type": "plane", "normal": [0, 1, 0], "distance": 0},)"
      << "\n"
      << objects << "]}";
    return s.str();
}

struct Options {
    int reps = 3, threads = 2, max = 65536, maxOff = 16384, parseN = 100000;
    bool buildOnly = false;
    std::string tracer = "default";  // or classic (Hart's), segment (Galin et al.'s)
    std::vector<std::string> kinds{"clusters", "city", "molecule", "sculpt"};
    std::vector<std::string> views{"above", "close", "grazing"};
};

struct Run {
    double planMs = 0, renderMs = 0, evalsPerPixel = 0;
    std::vector<float> depth;
    // The render's wall time over every evaluation it made.
    double nsPerEval() const { return 1e6 * renderMs / (evalsPerPixel * kWidth * kHeight); }
};

Run renderScene(const Scene& parsed, bool pruning, const Options& o) {
    Scene s = parsed;
    s.settings.pruning = pruning;
    s.settings.threads = o.threads;
    if (o.tracer == "classic") s.settings.trace = TraceOptions::classic();
    if (o.tracer == "segment") s.settings.trace.segmentTracing = true;
    Run r;
    const auto t0 = Clock::now();
    const RenderPlan plan = planRender(s);
    r.planMs = ms(t0, Clock::now());
    std::vector<double> times;
    for (int k = 0; k < o.reps; ++k) {
        Film film(plan.camera.width, plan.camera.height, Film::bit(Aov::Depth));
        const auto a = Clock::now();
        const RenderStats st = render(plan, film);
        times.push_back(ms(a, Clock::now()));
        r.evalsPerPixel = static_cast<double>(st.primaryEvaluations + st.normalEvaluations +
                                              st.shadowEvaluations + st.aoEvaluations) /
                          static_cast<double>(film.pixels());
        r.depth = film.depth;
    }
    std::sort(times.begin(), times.end());
    r.renderMs = times[times.size() / 2];
    return r;
}

long depthMismatches(const std::vector<float>& a, const std::vector<float>& b) {
    long bad = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        const bool ha = std::isfinite(a[i]), hb = std::isfinite(b[i]);
        if (ha != hb || (ha && std::fabs(a[i] - b[i]) > 1e-4f * std::max(a[i], b[i]))) ++bad;
    }
    return bad;
}

std::string objectsOf(const std::string& kind, int n) {
    std::mt19937 rng(1234u + static_cast<unsigned>(n));
    return kind == "clusters"   ? clusters(n, rng)
           : kind == "city"     ? city(n, rng)
           : kind == "molecule" ? molecule(n, rng)
                                : sculpt(n, rng);
}

void row(const std::string& kind, int n, const std::string& view, const Options& o) {
    const std::string text = sceneText(objectsOf(kind, n), n, view);
    auto t0 = Clock::now();
    const Scene scene = parseSceneText(text, kind + ".json");
    const double parseMs = ms(t0, Clock::now());
    const Run on = renderScene(scene, true, o);
    const double nsOn = on.nsPerEval();
    if (n > o.maxOff) {
        std::printf(
            "| %s | %s | %d | %.0f ms | %.1f ms | %.1f | %.1f ms | %.0f ns | — | — | — | — | — |\n",
            kind.c_str(), view.c_str(), n, parseMs, on.planMs, on.evalsPerPixel, on.renderMs, nsOn);
    } else {
        const Run off = renderScene(scene, false, o);
        const double nsOff = off.nsPerEval();
        std::printf(
            "| %s | %s | %d | %.0f ms | %.1f ms | %.1f | %.1f ms | %.0f ns | %.1f | %.1f ms | "
            "%.0f ns | %.2fx | %ld |\n",
            kind.c_str(), view.c_str(), n, parseMs, on.planMs - off.planMs, on.evalsPerPixel,
            on.renderMs, nsOn, off.evalsPerPixel, off.renderMs, nsOff, off.renderMs / on.renderMs,
            depthMismatches(on.depth, off.depth));
    }
    std::fflush(stdout);
}

void parseRow(const std::string& kind, int n, const Options& o) {
    const std::string text = sceneText(objectsOf(kind, n), n, "above");
    std::vector<double> times;
    for (int k = 0; k < std::max(1, o.reps); ++k) {
        const auto t0 = Clock::now();
        const Scene scene = parseSceneText(text, kind + ".json");
        times.push_back(ms(t0, Clock::now()));
        if (!scene.root) std::abort();
    }
    std::sort(times.begin(), times.end());
    std::printf("| %s | %d | %.1f MB | %.0f ms |\n", kind.c_str(), n, text.size() / 1e6,
                times[times.size() / 2]);
    std::fflush(stdout);
}

// The pruned cells' build alone (--build-only 1): compileTape with pruning on less off, median
// of --reps; the leaf cells, their distinct tapes and the bytes they take, and the entries of a
// leaf cell's tape on average (an instruction, or a Run of the whole tape's).
void buildRow(const std::string& kind, int n, const Options& o) {
    const Scene scene = parseSceneText(sceneText(objectsOf(kind, n), n, "above"), kind + ".json");
    std::vector<double> on, off;
    Tape tape;
    for (int k = 0; k < std::max(1, o.reps); ++k) {
        const auto t0 = Clock::now();
        const Tape whole = compileTape(scene.root, {.boundsCulling = true, .pruning = false});
        const auto t1 = Clock::now();
        tape = compileTape(scene.root, {.boundsCulling = true, .pruning = true});
        off.push_back(ms(t0, t1));
        on.push_back(ms(t1, Clock::now()));
    }
    std::sort(on.begin(), on.end());
    std::sort(off.begin(), off.end());
    const PrunedTapes* p = tape.pruned();
    double meanLeaf = 0;
    if (p) {
        for (uint32_t t : p->cellTape) meanLeaf += p->spans[2 * t + 1];
        meanLeaf /= static_cast<double>(p->cellTape.size());
    }
    std::printf("| %s | %d | %zu | %.1f ms | %.1f ms | %zu | %zu | %.1f MB | %.0f |\n",
                kind.c_str(), n, tape.size(), off[off.size() / 2],
                on[on.size() / 2] - off[off.size() / 2], p ? p->cellTape.size() : 0,
                p ? p->spans.size() / 2 : 0,
                p ? static_cast<double>(p->instrs.size() * sizeof(Instr)) / 1e6 : 0.0, meanLeaf);
    std::fflush(stdout);
}

}  // namespace
}  // namespace sdft

int main(int argc, char** argv) {
    sdft::Options o;
    constexpr const char* kUsage =
        "usage: sdftrace_pruning_bench [--reps 3] [--threads 2] [--max 65536] [--max-off 4096]\n"
        "       [--kinds clusters,city,molecule,sculpt] [--views above,close,grazing]\n"
        "       [--tracer default|classic|segment] [--build-only 0|1] [--parse N]\n";
    if (const int status = sdft::bench::checkFlagPairs(argc, argv, kUsage); status >= 0)
        return status;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string a = argv[i], v = argv[i + 1];
        if (a == "--reps")
            o.reps = sdft::bench::intFlag(a, v);
        else if (a == "--threads")
            o.threads = sdft::bench::intFlag(a, v);
        else if (a == "--max")
            o.max = sdft::bench::intFlag(a, v);
        else if (a == "--max-off")
            o.maxOff = sdft::bench::intFlag(a, v, 0);
        else if (a == "--build-only")
            o.buildOnly = v != "0";
        else if (a == "--parse")
            o.parseN = sdft::bench::intFlag(a, v);
        else if (a == "--tracer") {
            if (v != "default" && v != "classic" && v != "segment")
                sdft::bench::badValue(a, v, "default, classic or segment");
            o.tracer = v;
        } else if (a == "--kinds" || a == "--views") {
            std::vector<std::string>& list = a == "--kinds" ? o.kinds : o.views;
            list.clear();
            std::stringstream s(v);
            for (std::string k; std::getline(s, k, ',');) list.push_back(k);
        } else {
            std::fprintf(stderr, "unknown option %s\n", a.c_str());
            return 2;
        }
    }
    if (o.buildOnly) {
        const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, o.threads);
        std::printf(
            "| scene | N | tape | compile | pruning build | leaf cells | tapes | their size | "
            "entries per leaf tape |\n|---|---|---|---|---|---|---|---|---|\n");
        for (const std::string& kind : o.kinds)
            for (int n = 64; n <= o.max; n *= 4) sdft::buildRow(kind, n, o);
        return 0;
    }
    std::printf("## Pruning: %d threads, %dx%d, no shadows, medians of %d, %s tracer\n\n",
                o.threads, sdft::kWidth, sdft::kHeight, o.reps, o.tracer.c_str());
    std::printf(
        "| scene | camera | N | parse | pruning build | evals / pixel | frame | per eval | "
        "evals / pixel (off) | frame (off) | per eval (off) | frame speed-up | depth mismatches |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const std::string& kind : o.kinds)
        for (const std::string& view : o.views)
            for (int n = 64; n <= o.max; n *= 4) sdft::row(kind, n, view, o);
    // Scene files of many primitives: the JSON parse alone (text to tree), median of --reps.
    if (o.parseN > 0) {
        std::printf("\n| scene | N | JSON size | parse |\n|---|---|---|---|\n");
        for (const std::string& kind : o.kinds) sdft::parseRow(kind, o.parseN, o);
    }
    return 0;
}
