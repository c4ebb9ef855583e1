// The image being rendered: linear colour and the AOVs (arbitrary output variables).
#pragma once

#include <string>
#include <vector>

#include "sdftrace/math/vec.h"

namespace sdft {

enum class Aov { Color, Depth, Normal, Steps, Error, TravSteps, IsectTests, Shadow, Ao, Motion };

// Names as on the command line: color, depth, normal, steps, error, trav_steps, isect_tests,
// shadow, ao, motion.
const char* aovName(Aov aov);
bool parseAov(const std::string& name, Aov& out);
int aovChannels(Aov aov);

struct Film {
    int width = 0, height = 0;
    std::vector<float> color;      // 3 per pixel: linear radiance before tone mapping
    std::vector<float> depth;      // t along the unit primary ray, +inf on a miss
    std::vector<float> normal;     // 3 per pixel, zero on a miss
    std::vector<float> steps;      // field evaluations of the primary ray
    std::vector<float> error;      // f where the march placed the hit (before root refinement)
    std::vector<float> travSteps;  // grid tracer: blocks + cells visited by primary and shadow rays
    std::vector<float>
        isectTests;  // grid tracer: surface-cell intersection tests (Jamriška fig. 7)
    // visibility of the first light that casts shadows (0 where its centre is below the
    // horizon); 1 on a miss
    std::vector<float> shadow;
    std::vector<float> ao;  // ambient occlusion (1: none, or off); 1 on a miss
    // 2 per pixel: where the pixel's surface was in the previous frame's image minus where it is
    // (pixels, +y down; motion.h); zero on a miss and in stills. Filled by animations, not by
    // render().
    std::vector<float> motion;

    // Which AOVs a film keeps, one bit per Aov (color always): the others stay empty and are
    // not written, so a plain render does not fill 15 floats a pixel to keep 3.
    static constexpr unsigned kAllAovs = 0x3ff;
    static constexpr unsigned bit(Aov aov) { return 1u << static_cast<unsigned>(aov); }

    explicit Film(int w, int h, unsigned aovs = kAllAovs);
    bool has(Aov aov) const { return !channel(aov).empty(); }
    size_t pixels() const { return static_cast<size_t>(width) * height; }
    // Bytes a film of this size needs with every AOV (to refuse absurd sizes before allocating).
    static double bytesNeeded(int w, int h);
    // Interleaved channels of one AOV.
    const std::vector<float>& channel(Aov aov) const;
    std::vector<float>& channel(Aov aov) {
        return const_cast<std::vector<float>&>(static_cast<const Film&>(*this).channel(aov));
    }
};

}  // namespace sdft
