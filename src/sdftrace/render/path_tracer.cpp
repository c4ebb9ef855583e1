#include "sdftrace/render/path_tracer.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "sdftrace/exec/progress.h"
#include "sdftrace/exec/thread_arena.h"
#include "sdftrace/math/camera.h"
#include "sdftrace/math/sampling.h"
#include "sdftrace/render/light_sample.h"
#include "sdftrace/render/path_pixel.h"
#include "sdftrace/trace/field_tracer.h"
#include "sdftrace/trace/sphere_tracer.h"

namespace sdft {

namespace {

// The CPU's paths: pathRadiance (path_pixel.h) with direct_pixel.h's materialAt (textures
// included), its counters added to the frame's.
class PathTracer {
  public:
    PathTracer(const RenderPlan& plan, const FrameView& view)
        : m_tables(directPixelTables(plan)), m_view(pathPixelView(plan, view, m_tables)) {}

    Vec3 radiance(int x, int y, int sample, RenderStats& st, float* depth, Vec3* normal,
                  int* steps) const {
        const auto materialAt = [this](Vec3 p, Vec3 n) {
            return direct_pixel::materialAt<kTapeMaxScalarRegs>(m_view.direct, p, n);
        };
        PathCounters c;
        const Vec3 L = pathRadiance(m_view, materialAt, x, y, sample, c, depth, normal, steps);
        st.primaryRays += c.primaryRays;
        st.primaryEvaluations += c.primaryEvaluations;
        st.hits += c.hits;
        st.normalEvaluations += c.normalEvaluations;
        st.shadowRays += c.shadowRays;
        st.shadowEvaluations += c.shadowEvaluations;
        st.secondaryRays += c.secondaryRays;
        st.secondaryEvaluations += c.secondaryEvaluations;
        return L;
    }

  private:
    DirectPixelTables m_tables;
    PathPixelView m_view;
};

}  // namespace

struct PathFrame::Impl {
    Impl(const RenderPlan& plan, const FrameView& view, Film& f) : tracer(plan, view), film(f) {}
    PathTracer tracer;
    Film& film;
    int spp = 1;
};

PathFrame::PathFrame(const RenderPlan& plan, const FrameView& view, Film& film)
    : m_impl(std::make_unique<Impl>(plan, view, film)) {
    m_impl->spp = std::max(1, plan.settings.samplesPerPixel);
}

PathFrame::~PathFrame() = default;

void PathFrame::render(const PixelRect& r, RenderStats& st) const {
    Film& film = m_impl->film;
    const int spp = m_impl->spp;
    const bool normals = film.has(Aov::Normal), depths = film.has(Aov::Depth),
               keepSteps = film.has(Aov::Steps);
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) {
            const size_t p = static_cast<size_t>(y) * film.width + x;
            Vec3 sum(0.0f), normal(0.0f);
            float depth = INFINITY;
            int steps = 0;
            for (int k = 0; k < spp; ++k)
                sum +=
                    m_impl->tracer.radiance(x, y, k, st, k == 0 ? &depth : nullptr,
                                            k == 0 ? &normal : nullptr, k == 0 ? &steps : nullptr);
            const Vec3 c = sum / static_cast<float>(spp);
            for (int a = 0; a < 3; ++a) {
                film.color[3 * p + a] = c[a];
                if (normals) film.normal[3 * p + a] = normal[a];
            }
            if (depths) film.depth[p] = depth;
            if (keepSteps) film.steps[p] = static_cast<float>(steps);
        }
}

RenderStats renderPaths(const RenderPlan& plan, const FrameView& view, Film& film, bool progress) {
    FrameRenderer frame(plan, view, film);
    Progress bar("path tracing", static_cast<uint64_t>(frame.tileCount()), progress);
    frame.renderTiles(0, frame.tileCount(), &bar);
    return frame.stats();
}

}  // namespace sdft
