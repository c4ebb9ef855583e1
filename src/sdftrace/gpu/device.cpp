#include "sdftrace/gpu/device.h"

#include "sdftrace/core/error.h"
#include "sdftrace/gpu/gpu_bake.h"
#include "sdftrace/gpu/gpu_device.h"
#include "sdftrace/gpu/gpu_render.h"
#include "sdftrace/render/direct_pixel.h"
#include "sdftrace/render/renderer.h"

namespace sdft {

const char* deviceName(Device d) {
    switch (d) {
        case Device::Cpu:
            return "cpu";
        case Device::Cuda:
            return "cuda";
        case Device::Auto:
            return "auto";
    }
    return "?";
}

bool parseDevice(const std::string& name, Device& out) {
    for (Device d : {Device::Cpu, Device::Cuda, Device::Auto}) {
        if (name == deviceName(d)) {
            out = d;
            return true;
        }
    }
    return false;
}

namespace {

// The common rule: `unsupported` is what the GPU lacks for this work (empty: nothing).
DeviceChoice choose(Device asked, const std::string& unsupported, const std::string& what) {
    if (asked == Device::Cpu) return {};
    if (asked == Device::Cuda) {
        // What the GPU does not do is refused wherever this runs, then a missing backend or
        // device: one line either way, before any work.
        if (!unsupported.empty()) throw InputError(what + ": " + unsupported);
        requireGpu(what);
        return {true, ""};
    }
    if (!unsupported.empty()) return {false, unsupported};
    if (!gpuInfo().present) return {false, gpuInfo().why};
    return {true, ""};
}

}  // namespace

DeviceChoice chooseRenderDevice(Device asked, const RenderPlan& plan, const std::string& what) {
    const std::string unsupported = directPixelUnsupported(plan);
    return choose(
        asked, unsupported.empty() ? "" : "the GPU does not render " + unsupported + " yet", what);
}

DeviceChoice chooseBakeDevice(Device asked, const MeshBakeOptions& options,
                              const std::string& what) {
    return choose(asked, gpuBakeUnsupported(options), what);
}

MeshBakeResult bakeMeshOn(bool gpu, const TriangleMesh& mesh, const MeshBakeOptions& options) {
    return gpu ? bakeMeshGpu(mesh, options) : bakeMesh(mesh, options);
}

struct PlanRenderer::Gpu {
    GpuDirectRenderer renderer;
};

PlanRenderer::PlanRenderer(const RenderPlan& plan, Device asked, const std::string& what)
    : m_plan(&plan), m_choice(chooseRenderDevice(asked, plan, what)) {
    if (m_choice.gpu) m_gpu = std::make_unique<Gpu>(Gpu{GpuDirectRenderer(plan, what)});
}

PlanRenderer::~PlanRenderer() = default;
PlanRenderer::PlanRenderer(PlanRenderer&&) noexcept = default;

bool PlanRenderer::gpu() const { return m_gpu != nullptr; }

RenderStats PlanRenderer::render(const FrameView& view, Film& film, bool progress) const {
    if (m_gpu) return m_gpu->renderer.render(view, film);
    return sdft::render(*m_plan, view, film, progress);
}

FrameRenderFn PlanRenderer::frames() const {
    if (!m_gpu) return nullptr;
    const GpuDirectRenderer* gpu = &m_gpu->renderer;
    return [gpu](const FrameView& view, Film& film, bool) { return gpu->render(view, film); };
}

}  // namespace sdft
