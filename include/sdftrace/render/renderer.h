// The direct-lighting renderer: tiles of primary rays traced as packets, gradient normals,
// Lambert + Blinn-Phong shading, shadows by the settings' method (hard rays, Liktor 2008 §4.1;
// SDF soft shadows, RTSDF §2.4-2.5; distributed rays; shadow maps with PCF or EVSM), and SDF
// ambient occlusion. Shadow-map evaluations count as shadow evaluations.
#pragma once

#include <cstdint>

#include "sdftrace/field/tape.h"
#include "sdftrace/render/film.h"
#include "sdftrace/scene/scene.h"

namespace sdft {

struct RenderStats {
    double seconds = 0;
    int threads = 0;
    uint64_t primaryRays = 0, primaryEvaluations = 0, hits = 0, fallbacks = 0;
    uint64_t normalEvaluations = 0, shadowRays = 0, shadowEvaluations = 0, aoEvaluations = 0;
    // Whitted reflection and refraction rays, their evaluations, and those that struck the
    // surface they left within twice their offset (Keinert §3.3's self-intersections).
    uint64_t secondaryRays = 0, secondaryEvaluations = 0, selfIntersections = 0;
    // Single-grid scenes traced by DDA (Jamriška): blocks + cells visited, surface cells tested.
    uint64_t traversalSteps = 0, intersectionTests = 0;
    bool gridTracer = false;

    // Sums the counters of `o` (per-thread or per-tile statistics); not seconds, threads or flags.
    void add(const RenderStats& o) {
        primaryRays += o.primaryRays;
        primaryEvaluations += o.primaryEvaluations;
        hits += o.hits;
        fallbacks += o.fallbacks;
        normalEvaluations += o.normalEvaluations;
        shadowRays += o.shadowRays;
        shadowEvaluations += o.shadowEvaluations;
        aoEvaluations += o.aoEvaluations;
        secondaryRays += o.secondaryRays;
        secondaryEvaluations += o.secondaryEvaluations;
        selfIntersections += o.selfIntersections;
        traversalSteps += o.traversalSteps;
        intersectionTests += o.intersectionTests;
    }

    uint64_t totalEvaluations() const {
        return primaryEvaluations + normalEvaluations + shadowEvaluations + aoEvaluations +
               secondaryEvaluations;
    }
};

// Renders the scene into the film (sized from scene.camera). `progress` prints on stderr.
RenderStats render(const Scene& scene, const Tape& tape, Film& film, bool progress = false);

// Unit gradient of the field at p by central differences (6 evaluations) or the tetrahedral
// 4-tap estimate, with step h.
Vec3 estimateNormal(const Tape& tape, Vec3 p, float h, NormalEstimator estimator);

}  // namespace sdft
