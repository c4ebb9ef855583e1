// The GPU entry points of a build without the CUDA backend (CMake's SDFT_CUDA found no nvcc or was
// OFF): every request for a GPU is one clear error, and gpuInfo() says why.
#include "sdftrace/core/error.h"
#include "sdftrace/gpu/gpu_bake.h"
#include "sdftrace/gpu/gpu_complete_grid.h"
#include "sdftrace/gpu/gpu_device.h"
#include "sdftrace/gpu/gpu_primary.h"
#include "sdftrace/gpu/gpu_render.h"
#include "sdftrace/gpu/gpu_tape.h"

namespace sdft {

const GpuInfo& gpuInfo() {
    static const GpuInfo info = [] {
        GpuInfo i;
        i.why =
            "this build of sdftrace has no CUDA backend (configure with -DSDFT_CUDA=ON where "
            "nvcc is installed)";
        return i;
    }();
    return info;
}

int useGpuOfLocalRank(int) { return -1; }

void requireGpu(const std::string& what) { throw InputError(what + ": " + gpuInfo().why); }

struct GpuTape::Impl {};

GpuTape::GpuTape(const Tape&, const std::vector<GpuGridBinding>&) { requireGpu("GPU tape"); }
void GpuTape::rebind(const GpuGridBinding&) {}
GpuTape::~GpuTape() = default;
GpuTape::GpuTape(GpuTape&&) noexcept = default;
GpuTape& GpuTape::operator=(GpuTape&&) noexcept = default;
const TapeView& GpuTape::view() const {
    static const TapeView none;
    return none;
}
size_t GpuTape::deviceBytes() const { return 0; }

GpuPrimaryImage tracePrimaryGpu(const GpuTape&, const PrimaryPixelView&, int, int) {
    requireGpu("GPU primary rays");
    return {};
}

GpuMinMax buildMinMaxGpu(const GpuTape&, int, const GridView&, const Camera&, int) {
    requireGpu("GPU min/max buffer");
    return {};
}

struct GpuDirectRenderer::Impl {};

GpuDirectRenderer::GpuDirectRenderer(const RenderPlan&, const std::string& what,
                                     const std::vector<GpuGridBinding>&) {
    requireGpu(what);
}
void GpuDirectRenderer::rebind(const GpuGridBinding&) {}
void GpuDirectRenderer::followMesh(int, std::shared_ptr<RtsdfDeviceState>) {}
GpuDirectRenderer::~GpuDirectRenderer() = default;
GpuDirectRenderer::GpuDirectRenderer(GpuDirectRenderer&&) noexcept = default;
GpuDirectRenderer& GpuDirectRenderer::operator=(GpuDirectRenderer&&) noexcept = default;
RenderStats GpuDirectRenderer::render(const FrameView&, Film&) const {
    requireGpu("GPU render");
    return {};
}

struct GpuCompleteGrid::Impl {};

GpuCompleteGrid::GpuCompleteGrid(const Grid&) { requireGpu("GPU complete grid"); }
GpuCompleteGrid::~GpuCompleteGrid() = default;
GpuCompleteGrid::GpuCompleteGrid(GpuCompleteGrid&&) noexcept = default;
GpuCompleteGrid& GpuCompleteGrid::operator=(GpuCompleteGrid&&) noexcept = default;
void GpuCompleteGrid::refresh(const float*, GpuRefreshTimes*) {}
void GpuCompleteGrid::refreshFromHost(const std::vector<float>&, GpuRefreshTimes*) {}
const GridView& GpuCompleteGrid::view() const {
    static const GridView none;
    return none;
}
GpuCompleteGridArrays GpuCompleteGrid::download() const { return {}; }

struct GpuMeshBaker::Impl {};

GpuMeshBaker::GpuMeshBaker(const TriangleMesh&, GpuWinding) { requireGpu("GPU bake"); }
GpuMeshBaker::~GpuMeshBaker() = default;
GpuMeshBaker::GpuMeshBaker(GpuMeshBaker&&) noexcept = default;
GpuMeshBaker& GpuMeshBaker::operator=(GpuMeshBaker&&) noexcept = default;
double GpuMeshBaker::lbvhBuildMs() const { return 0; }
size_t GpuMeshBaker::deviceBytes() const { return 0; }
std::vector<float> GpuMeshBaker::jumpFlood(const GridShape&, JfaVariant, SignMethod, float,
                                           GpuBakeTimes*) const {
    return {};
}
std::vector<float> GpuMeshBaker::rtsdf(const GridShape&, const RtsdfOptions&, RtsdfStats*,
                                       GpuBakeTimes*) const {
    return {};
}
void GpuMeshBaker::pose(const TriangleMesh&, GpuBakeTimes*) {}
std::vector<float> GpuMeshBaker::accumulate(const GridShape&, const RtsdfOptions&, float,
                                            const RtsdfHistory*, RtsdfStats*, GpuBakeTimes*) {
    return {};
}
const float* GpuMeshBaker::accumulateOnDevice(const GridShape&, const RtsdfOptions&, float,
                                              const RtsdfHistory*, RtsdfStats*, GpuBakeTimes*) {
    return nullptr;
}
int GpuMeshBaker::accumulatedFrames() const { return 0; }
GpuMeshSurface GpuMeshBaker::surface() const { return {}; }
SurfaceSeeds GpuMeshBaker::seeds(const GridShape&) const { return {}; }
std::vector<Vec3> GpuMeshBaker::jumpFloodPoints(const GridShape&, const std::vector<Vec3>&,
                                                JfaVariant, GpuBakeTimes*) const {
    return {};
}
std::vector<LbvhHit> GpuMeshBaker::firstHits(const std::vector<Ray>&, float) const { return {}; }
std::vector<WindingNode> GpuMeshBaker::windingNodes() const { return {}; }
std::vector<float> GpuMeshBaker::windingCorners() const { return {}; }

}  // namespace sdft
