// The material at a surface point: the tape's material blend (smooth blends and morphs mix
// materials with their weights, Keinert et al. 2014 §4), with textured colours looked up in each
// material's object frame (texture.h).
#pragma once

#include "sdftrace/field/tape.h"
#include "sdftrace/render/render_plan.h"

namespace sdft {

// n: the unit world normal at p (for tri-planar projections).
Material materialAt(const RenderPlan& plan, Vec3 p, Vec3 n);

}  // namespace sdft
