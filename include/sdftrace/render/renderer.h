// The direct-lighting renderer: tiles of primary rays traced as packets, gradient normals,
// Lambert + Blinn-Phong shading, shadows by the settings' method (hard rays, Liktor 2008 §4.1;
// SDF soft shadows, RTSDF §2.4-2.5; distributed rays; shadow maps with PCF or EVSM), and SDF
// ambient occlusion. Shadow-map evaluations count as shadow evaluations. A plan whose settings ask
// for the path tracer is handed to it (path_tracer.h).
#pragma once

#include "sdftrace/field/tape.h"
#include "sdftrace/render/film.h"
#include "sdftrace/render/render_plan.h"
#include "sdftrace/render/render_settings.h"
#include "sdftrace/render/render_stats.h"

namespace sdft {

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
