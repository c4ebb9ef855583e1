// Where work runs, as the library's choice: the CPU, the GPU (CUDA), or the GPU where one can do
// the work and the CPU otherwise. `sdftrace render|bake --device`, Python's `device=` and any
// program using the library resolve a request here, so that each says the same thing when the
// GPU cannot be used: `cuda` insists (an error naming what is missing, before any work), `auto`
// falls back to the CPU with one line saying why.
#pragma once

#include <memory>
#include <string>

#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/render/film.h"
#include "sdftrace/render/render_plan.h"
#include "sdftrace/render/render_stats.h"
#include "sdftrace/render/temporal.h"

namespace sdft {

enum class Device { Cpu, Cuda, Auto };

const char* deviceName(Device d);  // "cpu", "cuda", "auto"
// The names above; false if unknown.
bool parseDevice(const std::string& name, Device& out);
inline constexpr const char* kDevices = "cpu, cuda, auto";

// What a request resolved to: the GPU, or the CPU and why (empty when the CPU was asked for).
struct DeviceChoice {
    bool gpu = false;
    std::string why;
};

// The device that renders `plan`. Cuda: the GPU, or InputError "<what>: ..." when this build has
// no CUDA backend, no device answers, or the GPU does not render something the plan asks for.
// Auto: the GPU where it can, else the CPU and why.
DeviceChoice chooseRenderDevice(Device asked, const RenderPlan& plan, const std::string& what);
// The device that bakes a mesh with `options` (gpuBakeUnsupported's methods and signs), alike.
DeviceChoice chooseBakeDevice(Device asked, const MeshBakeOptions& options,
                              const std::string& what);

// bakeMesh (mesh_bake.h) on the GPU where `gpu` (bakeMeshGpu: a choice of chooseBakeDevice), else
// on the CPU.
MeshBakeResult bakeMeshOn(bool gpu, const TriangleMesh& mesh, const MeshBakeOptions& options);

// A plan's renderer on the chosen device: the GPU renderer (its tapes and tables uploaded once,
// its frame buffers kept) or the CPU's tiles. The plan must outlive it.
class PlanRenderer {
  public:
    PlanRenderer(const RenderPlan& plan, Device asked, const std::string& what);
    ~PlanRenderer();
    PlanRenderer(PlanRenderer&&) noexcept;

    bool gpu() const;
    // Why the CPU renders where auto was asked (empty otherwise): for the one-line note.
    const std::string& why() const { return m_choice.why; }
    RenderStats render(const FrameView& view, Film& film, bool progress = false) const;
    // As renderFrames' renderFrame (temporal.h): nullptr on the CPU (renderFrames' own).
    FrameRenderFn frames() const;

  private:
    const RenderPlan* m_plan;
    DeviceChoice m_choice;
    struct Gpu;
    std::unique_ptr<Gpu> m_gpu;
};

}  // namespace sdft
