// A frame rendered across the job's ranks (docs/cluster.md): its tiles dealt by the work farm,
// each rank rendering with its own threads through a FrameRenderer of the same plan, and the
// pixels gathered into rank 0's film. Every pixel depends only on the plan, the view and the
// pixel, so the image is the single-process one bit for bit.
#pragma once

#include <functional>
#include <memory>

#include "sdftrace/cluster/work_farm.h"
#include "sdftrace/render/film.h"
#include "sdftrace/render/render_plan.h"
#include "sdftrace/render/render_stats.h"

namespace sdft {

// Renders one frame on the whole job (rank 0). Stats: every rank's counters; threads summed
// over the ranks.
// `prefix` leads the round's context (what the other ranks need to find the plan).
RenderStats renderAcross(WorkFarm& farm, const RenderPlan& plan, const FrameView& view, Film& film,
                         bool progress, Bytes prefix = {});

// The worker's side of renderAcross: the round's worker from the rest of its context (after the
// prefix), rendering `plan`, which must outlive it.
std::unique_ptr<RoundWorker> tileWorker(const RenderPlan& plan, ByteReader& context);

// The AOVs a film keeps, every pixel of them (channels in Aov order): frames sent whole.
void packFilm(const Film& film, ByteWriter& out);
// A film of packFilm's size and AOVs.
Film unpackFilm(ByteReader& in);

}  // namespace sdft
