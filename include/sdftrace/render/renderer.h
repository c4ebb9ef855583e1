// The direct-lighting renderer: tiles of primary rays traced as packets, gradient normals,
// Lambert + Blinn-Phong shading, shadows by the settings' method (hard rays, Liktor 2008 §4.1;
// SDF soft shadows, RTSDF §2.4-2.5; distributed rays; shadow maps with PCF or EVSM), and SDF
// ambient occlusion. Shadow-map evaluations count as shadow evaluations. A plan whose settings ask
// for the path tracer is handed to it (path_tracer.h).
#pragma once

#include <memory>

#include "sdftrace/field/tape.h"
#include "sdftrace/render/film.h"
#include "sdftrace/render/render_plan.h"
#include "sdftrace/render/render_settings.h"
#include "sdftrace/render/render_stats.h"

namespace sdft {

class Progress;

// The pixel rectangle [x0, x1) x [y0, y1).
struct PixelRect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

// One frame rendered tiles at a time (Jamriška 2010, §8: square tiles of the image dealt to the
// threads; here to the ranks of a job too), in any order and any grouping, by any process: a
// pixel's value depends only on the plan, the view and the pixel, so a frame split across threads
// or ranks (cluster/distributed_render.h) is the same image bit for bit. The frame's shared work
// (shadow maps) is done once, in the constructor. Tiles are plan.settings.tileSize squares in
// row-major order, the last row and column cut by the film.
class FrameRenderer {
  public:
    FrameRenderer(const RenderPlan& plan, const FrameView& view, Film& film);
    ~FrameRenderer();
    FrameRenderer(const FrameRenderer&) = delete;
    FrameRenderer& operator=(const FrameRenderer&) = delete;

    int tileCount() const;
    PixelRect tile(int index) const;
    // Renders tiles [first, last) in parallel into the film; `progress` advances per tile.
    void renderTiles(int first, int last, Progress* progress = nullptr);
    // The counters of every tile rendered so far, with the frame's shared work; seconds since
    // construction.
    RenderStats stats() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

// Renders the plan as seen by `view` into the film (sized from view.camera). `progress` prints
// on stderr.
RenderStats render(const RenderPlan& plan, const FrameView& view, Film& film,
                   bool progress = false);
// Frame 0 through the plan's own camera.
inline RenderStats render(const RenderPlan& plan, Film& film, bool progress = false) {
    return render(plan, FrameView{plan.camera}, film, progress);
}

// Unit gradient of the field at p by central differences (6 evaluations) or the tetrahedral
// 4-tap estimate, with step h.
Vec3 estimateNormal(const Tape& tape, Vec3 p, float h, NormalEstimator estimator);

}  // namespace sdft
