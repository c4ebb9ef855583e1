#include "sdftrace/render/film.h"

#include <tbb/parallel_invoke.h>

#include <limits>

#include "sdftrace/exec/huge_pages.h"

namespace sdft {

const char* aovName(Aov aov) {
    switch (aov) {
        case Aov::Color:
            return "color";
        case Aov::Depth:
            return "depth";
        case Aov::Normal:
            return "normal";
        case Aov::Steps:
            return "steps";
        case Aov::Error:
            return "error";
        case Aov::TravSteps:
            return "trav_steps";
        case Aov::IsectTests:
            return "isect_tests";
        case Aov::Shadow:
            return "shadow";
        case Aov::Ao:
            return "ao";
        case Aov::Motion:
            return "motion";
    }
    return "?";
}

bool parseAov(const std::string& name, Aov& out) {
    for (Aov a : {Aov::Color, Aov::Depth, Aov::Normal, Aov::Steps, Aov::Error, Aov::TravSteps,
                  Aov::IsectTests, Aov::Shadow, Aov::Ao, Aov::Motion}) {
        if (name == aovName(a)) {
            out = a;
            return true;
        }
    }
    return false;
}

int aovChannels(Aov aov) {
    if (aov == Aov::Motion) return 2;
    return (aov == Aov::Color || aov == Aov::Normal) ? 3 : 1;
}

Film::Film(int w, int h, unsigned aovs) : width(w), height(h) {
    // Up to 15 floats a pixel (60 MiB at 1024x1024): on huge pages, filled side by side.
    const size_t n = pixels();
    const float inf = std::numeric_limits<float>::infinity();
    auto keep = [&](std::vector<float>& v, Aov aov, size_t size, float value) {
        if (aov == Aov::Color || (aovs & bit(aov))) assignHuge(v, size, value);
    };
    tbb::parallel_invoke([&] { keep(color, Aov::Color, 3 * n, 0.0f); },
                         [&] { keep(normal, Aov::Normal, 3 * n, 0.0f); },
                         [&] {
                             keep(depth, Aov::Depth, n, inf);
                             keep(steps, Aov::Steps, n, 0.0f);
                         },
                         [&] {
                             keep(error, Aov::Error, n, 0.0f);
                             keep(travSteps, Aov::TravSteps, n, 0.0f);
                         },
                         [&] {
                             keep(isectTests, Aov::IsectTests, n, 0.0f);
                             keep(shadow, Aov::Shadow, n, 1.0f);
                             keep(ao, Aov::Ao, n, 1.0f);
                             keep(motion, Aov::Motion, 2 * n, 0.0f);
                         });
}

double Film::bytesNeeded(int w, int h) {
    return static_cast<double>(w) * static_cast<double>(h) * sizeof(float) * 15.0;
}

const std::vector<float>& Film::channel(Aov aov) const {
    switch (aov) {
        case Aov::Color:
            return color;
        case Aov::Depth:
            return depth;
        case Aov::Normal:
            return normal;
        case Aov::Steps:
            return steps;
        case Aov::Error:
            return error;
        case Aov::TravSteps:
            return travSteps;
        case Aov::IsectTests:
            return isectTests;
        case Aov::Shadow:
            return shadow;
        case Aov::Ao:
            return ao;
        case Aov::Motion:
            return motion;
    }
    return color;
}

}  // namespace sdft
