#include "sdftrace/trace/field_tracer.h"

#include "sdftrace/core/macros.h"

namespace sdft {

TraceResult traceRay(const Tape& tape, const RaySegment& seg, const TraceOptions& o) {
    return traceTapeRay(tape.view(), seg, o);
}

void tracePacket(const Tape& tape, std::span<const RaySegment> segments, const TraceOptions& o,
                 std::span<TraceResult> results, PacketScratch& sc) {
    SDFT_CHECK(results.size() == segments.size());
    size_t n = segments.size();
    float invL = 1.0f / tape.lipschitz();
    sc.states.resize(n);
    sc.active.clear();
    for (size_t i = 0; i < n; ++i) {
        sphereTraceBegin(sc.states[i], segments[i].ray, segments[i].tMin, segments[i].tMax,
                         tape.bounds(), o);
        if (!sc.states[i].done()) sc.active.push_back(static_cast<int>(i));
    }
    sc.x.resize(n);
    sc.y.resize(n);
    sc.z.resize(n);
    sc.f.resize(n);
    while (!sc.active.empty()) {
        int count = static_cast<int>(sc.active.size());
        for (int j = 0; j < count; ++j) {
            Vec3 p = sc.states[sc.active[j]].queryPoint();
            sc.x[j] = p.x;
            sc.y[j] = p.y;
            sc.z[j] = p.z;
        }
        tape.evalBatch(sc.x.data(), sc.y.data(), sc.z.data(), sc.f.data(), count, sc.batch);
        int kept = 0;
        for (int j = 0; j < count; ++j) {
            SphereTraceState& s = sc.states[sc.active[j]];
            sphereTraceAdvance(s, sc.f[j], invL, o);
            if (!s.done()) sc.active[kept++] = sc.active[j];
        }
        sc.active.resize(kept);
    }
    for (size_t i = 0; i < n; ++i) results[i] = sc.states[i].result;
}

}  // namespace sdft
