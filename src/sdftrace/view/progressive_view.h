// Progressive rendering for the viewer (Jamriška 2010's interactive tracer; Keinert et al. 2014's
// real-time scenes): after every change a preview at 1/4 resolution comes first, then full-
// resolution frames accumulate as `render --frames N` accumulates them (the same jitter, seeds and
// running mean), so a view that stopped moving ends as the CLI's image of the same camera and
// settings, bit for bit.
#pragma once
#include <functional>
#include <optional>

#include "sdftrace/render/film.h"
#include "sdftrace/render/render_plan.h"
#include "sdftrace/render/render_stats.h"
#include "sdftrace/render/temporal.h"

namespace sdft {

struct ProgressiveOptions {
    int frames = 8;          // full-resolution frames accumulated (render --frames)
    int previewDivisor = 4;  // the preview's pixels: 1/4 of the width and of the height
    // What renders each plan's passes (view --device: a GPU's, gpu/device.h PlanRenderer), made
    // anew for each plan; null, or a null result: the CPU renderer.
    std::function<FrameRenderFn(const RenderPlan&)> renderer = nullptr;
};

class ProgressiveView {
  public:
    explicit ProgressiveView(ProgressiveOptions options = {}) : m_options(options) {}

    // A new plan (scene or settings) or camera: the next pass is a preview, the accumulation
    // starts again. The plan's camera is replaced by setCamera's.
    void setPlan(RenderPlan plan);
    void setCamera(const CameraDesc& camera);
    void setFrames(int frames);
    const CameraDesc& camera() const { return m_plan->camera; }
    bool hasPlan() const { return m_plan.has_value(); }
    const RenderPlan& plan() const { return *m_plan; }

    // Whether every full-resolution frame is done (nothing left to render).
    bool done() const;
    // Renders the next pass (the preview, else the next frame) and returns its statistics.
    RenderStats step();

    // The latest pass's film: the preview (small) until the first full frame, then the
    // accumulated full-resolution film (colour accumulated; the other AOVs the last frame's).
    const Film& film() const;
    bool showingPreview() const { return m_framesDone == 0; }
    int framesDone() const { return m_framesDone; }
    int frames() const { return m_options.frames; }
    const ProgressiveOptions& options() const { return m_options; }

  private:
    void restart();
    RenderStats renderPass(const FrameView& view, Film& film) const;

    ProgressiveOptions m_options;
    std::optional<RenderPlan> m_plan;
    std::optional<Film> m_preview, m_film;
    std::optional<TemporalAccumulator> m_history;
    FrameRenderFn m_render;  // the plan's renderer (options.renderer), or null: the CPU
    bool m_previewDone = false;
    int m_framesDone = 0;
};

}  // namespace sdft
