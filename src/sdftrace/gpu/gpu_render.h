// Direct lighting on the GPU (issue 14; `sdftrace render --device cuda`): one thread per pixel
// runs shadeDirectPixel (render/direct_pixel.h), the function DirectPixel.* holds to the CPU
// renderer, over device copies of the plan's tape, lights and materials, and the film gets the
// CPU renderer's colour and AOVs. Plain C++: no CUDA header here; without the CUDA backend every
// call is one clear error (gpu_absent.cpp).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "sdftrace/gpu/gpu_tape.h"
#include "sdftrace/render/film.h"
#include "sdftrace/render/render_plan.h"
#include "sdftrace/render/render_stats.h"

namespace sdft {

struct RtsdfDeviceState;  // gpu_bake.h

class GpuDirectRenderer {
  public:
    // Uploads `plan` (which must outlive this). Throws InputError "<what>: ..." when no GPU can
    // be used or the plan needs what the GPU path does not render yet (directPixelUnsupported);
    // `what` names the flag that asked (e.g. "--device cuda").
    // Grids in `bound` are already on the device (GpuCompleteGrid): the tapes read them there.
    GpuDirectRenderer(const RenderPlan& plan, const std::string& what,
                      const std::vector<GpuGridBinding>& bound = {});
    ~GpuDirectRenderer();
    GpuDirectRenderer(GpuDirectRenderer&&) noexcept;
    GpuDirectRenderer& operator=(GpuDirectRenderer&&) noexcept;

    // One frame into `film` (the plan camera's size): colour, and the depth, normal, steps,
    // error, shadow and AO AOVs the film keeps. The stats carry the GPU's times.
    RenderStats render(const FrameView& view, Film& film) const;
    // A bound grid's view anew, in every tape that reads it (after its refresh).
    void rebind(const GpuGridBinding& binding);
    // Triangle primaries: mesh `mesh` of the plan (in its order) as `state`'s baker poses it (in
    // the same coordinates), in place of its upload. The renderer keeps `state` alive and takes
    // the baker's arrays anew whenever it has posed since (GpuMeshBaker::poses), as it does for
    // the plan's own device meshes.
    void followMesh(int mesh, std::shared_ptr<RtsdfDeviceState> state);

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace sdft
