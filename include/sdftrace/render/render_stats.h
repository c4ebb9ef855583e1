// What a render did, for the summary line and the benches: rays, field evaluations by purpose,
// hits, over-relaxation fallbacks, Whitted and grid-traversal counters.
#pragma once

#include <cstdint>

namespace sdft {

struct RenderStats {
    double seconds = 0;
    int threads = 0;
    int ranks = 1;  // processes of a distributed render (cluster/distributed_render.h)
    uint64_t primaryRays = 0, primaryEvaluations = 0, hits = 0, fallbacks = 0;
    uint64_t normalEvaluations = 0, shadowRays = 0, shadowEvaluations = 0, aoEvaluations = 0;
    // Whitted reflection and refraction rays, their evaluations, and those that struck the
    // surface they left within twice their offset (Keinert §3.3's self-intersections).
    uint64_t secondaryRays = 0, secondaryEvaluations = 0, selfIntersections = 0;
    // Single-grid scenes traced by DDA (Jamriška): blocks + cells visited, surface cells tested.
    uint64_t traversalSteps = 0, intersectionTests = 0;
    bool gridTracer = false;
    // Rendered on a GPU (gpu/gpu_render.h): the kernels' time and the whole frame's (launches,
    // kernels and copies), summed over frames.
    bool gpu = false;
    double gpuKernelMs = 0, gpuFrameMs = 0;
    // Bytes copied between host and device for the frame (GPU renders): the AOVs asked for and
    // the counters' sums; the buffers themselves stay on the device between frames.
    uint64_t gpuBytesMoved = 0;

    // Sums the counters of `o` (per-thread, per-tile or per-frame statistics); not seconds,
    // threads or flags.
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

}  // namespace sdft
