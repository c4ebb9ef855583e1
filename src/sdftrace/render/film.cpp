#include "sdftrace/render/film.h"

#include <limits>

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
    }
    return "?";
}

bool parseAov(const std::string& name, Aov& out) {
    for (Aov a : {Aov::Color, Aov::Depth, Aov::Normal, Aov::Steps, Aov::Error, Aov::TravSteps,
                  Aov::IsectTests, Aov::Shadow, Aov::Ao}) {
        if (name == aovName(a)) {
            out = a;
            return true;
        }
    }
    return false;
}

int aovChannels(Aov aov) { return (aov == Aov::Color || aov == Aov::Normal) ? 3 : 1; }

Film::Film(int w, int h) : width(w), height(h) {
    size_t n = pixels();
    color.assign(3 * n, 0.0f);
    depth.assign(n, std::numeric_limits<float>::infinity());
    normal.assign(3 * n, 0.0f);
    steps.assign(n, 0.0f);
    error.assign(n, 0.0f);
    travSteps.assign(n, 0.0f);
    isectTests.assign(n, 0.0f);
    shadow.assign(n, 1.0f);
    ao.assign(n, 1.0f);
}

double Film::bytesNeeded(int w, int h) {
    return static_cast<double>(w) * static_cast<double>(h) * sizeof(float) * 13.0;
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
    }
    return color;
}

}  // namespace sdft
