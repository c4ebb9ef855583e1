#include "sdftrace/trace/field_tracer.h"

#include "sdftrace/core/macros.h"

namespace sdft {

TraceResult traceRay(const Tape& tape, const RaySegment& seg, const TraceOptions& o) {
    return traceTapeRay(tape.view(), seg, o);
}

namespace {

// One step of every active ray: their query points' values in one batch.
void stepPlain(const Tape& tape, float invL, const TraceOptions& o, PacketScratch& sc) {
    const int count = static_cast<int>(sc.active.size());
    for (int j = 0; j < count; ++j) {
        const Vec3 p = sc.states[sc.active[j]].queryPoint();
        sc.x[j] = p.x, sc.y[j] = p.y, sc.z[j] = p.z;
    }
    tape.evalBatch(sc.x.data(), sc.y.data(), sc.z.data(), sc.f.data(), count, sc.batch);
    for (int j = 0; j < count; ++j) sphereTraceAdvance(sc.states[sc.active[j]], sc.f[j], invL, o);
}

// One step of every active ray under segment tracing: the marching rays' values and slopes in one
// segment batch, the others' (refinement) values in one plain batch.
void stepSegments(const Tape& tape, float invL, const TraceOptions& o, PacketScratch& sc) {
    // The marching lanes fill the arrays from the front, the plain ones from the back.
    const size_t last = sc.x.size() - 1;
    int marching = 0, plain = 0;
    for (int i : sc.active) {
        const SphereTraceState& s = sc.states[i];
        const Vec3 p = s.queryPoint();
        if (sphereTraceWantsSegment(s, o)) {
            const int j = marching++;
            sc.x[j] = p.x, sc.y[j] = p.y, sc.z[j] = p.z;
            sc.ux[j] = s.ray.direction.x, sc.uy[j] = s.ray.direction.y,
            sc.uz[j] = s.ray.direction.z;
            sc.len[j] = sphereTraceSegment(s);
        } else {
            const size_t j = last - static_cast<size_t>(plain++);
            sc.x[j] = p.x, sc.y[j] = p.y, sc.z[j] = p.z;
        }
    }
    const SegmentLanes lanes{sc.x.data(),  sc.y.data(),   sc.z.data(), sc.ux.data(),   sc.uy.data(),
                             sc.uz.data(), sc.len.data(), sc.f.data(), sc.slope.data()};
    if (marching > 0) evalSegmentBatch(tape, lanes, marching, sc.segment);
    const size_t back = last + 1 - static_cast<size_t>(plain);
    if (plain > 0)
        tape.evalBatch(sc.x.data() + back, sc.y.data() + back, sc.z.data() + back,
                       sc.f.data() + back, plain, sc.batch);
    marching = 0, plain = 0;
    for (int i : sc.active) {
        SphereTraceState& s = sc.states[i];
        if (sphereTraceWantsSegment(s, o)) {
            const int j = marching++;
            sphereTraceAdvance(s, sc.f[j], invL, o, sc.slope[j], sc.len[j]);
        } else {
            sphereTraceAdvance(s, sc.f[last - static_cast<size_t>(plain++)], invL, o);
        }
    }
}

}  // namespace

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
    if (o.segmentTracing) {
        for (auto* v : {&sc.ux, &sc.uy, &sc.uz, &sc.len, &sc.slope}) v->resize(n);
    }
    while (!sc.active.empty()) {
        if (o.segmentTracing)
            stepSegments(tape, invL, o, sc);
        else
            stepPlain(tape, invL, o, sc);
        int kept = 0;
        for (int i : sc.active)
            if (!sc.states[i].done()) sc.active[kept++] = i;
        sc.active.resize(kept);
    }
    for (size_t i = 0; i < n; ++i) results[i] = sc.states[i].result;
}

}  // namespace sdft
