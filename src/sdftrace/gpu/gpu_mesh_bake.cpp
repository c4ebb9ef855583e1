// bakeMesh on the GPU (gpu_bake.h): what the GPU bakes, and the result assembled as the CPU's
// (stages, details, a sparse grid from the dense samples). Built with and without CUDA: without
// it, GpuMeshBaker answers with gpu_absent.cpp's one line.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>

#include "sdftrace/core/error.h"
#include "sdftrace/gpu/gpu_bake.h"
#include "sdftrace/gpu/gpu_device.h"

namespace sdft {

std::string gpuBakeUnsupported(const MeshBakeOptions& o) {
    if (o.method != MeshBakeMethod::JumpFlood && o.method != MeshBakeMethod::Rtsdf)
        return std::string("--method ") + meshBakeMethodName(o.method) +
               " runs on the CPU only (the GPU bakes jfa and rtsdf)";
    if (o.sign == SignMethod::RayParity || o.sign == SignMethod::FloodFill)
        return std::string("--sign ") + (o.sign == SignMethod::RayParity ? "parity" : "flood") +
               " runs on the CPU only (the GPU signs by winding" +
               (o.method == MeshBakeMethod::JumpFlood ? " or beta)" : ")");
    return "";
}

namespace {

// Whether complete grid `g` is the one finishMeshBake makes of a frame of `shape` and `so`.
bool sameCompleteLayout(const Grid& g, const GridShape& shape, const SampleOptions& so) {
    const GridShape& s = g.shape();
    return g.isComplete() && g.blockSize() == so.blockSize &&
           g.completeBand() == so.bandVoxels * shape.voxelSize && s.voxelSize == shape.voxelSize &&
           s.origin.x == shape.origin.x && s.origin.y == shape.origin.y &&
           s.origin.z == shape.origin.z && std::equal(s.cells, s.cells + 3, shape.cells);
}

std::string millis(double ms) {
    char s[32];
    std::snprintf(s, sizeof s, "%.2f ms", ms);
    return s;
}

}  // namespace

namespace {

// The rays' counts and the passes' GPU times of an RTSDF frame, for the summary line.
std::string rtsdfDetails(const RtsdfStats& st, int rays, const GpuMeshBaker& baker,
                         const GpuBakeTimes& t, const std::string& last) {
    char line[400];
    std::snprintf(line, sizeof line,
                  "%zu vertices refined by %d rays each (%zu rays), %zu with no hit; GPU: lbvh %s, "
                  "seeds %s, jfa %s, signs %s, rays %s, %s",
                  st.refined, rays, st.rays, st.missed, millis(baker.lbvhBuildMs()).c_str(),
                  millis(t.seedMs).c_str(), millis(t.jfaMs).c_str(), millis(t.signMs).c_str(),
                  millis(t.rayMs).c_str(), last.c_str());
    return line;
}

// A later RTSDF frame for a GPU renderer (MeshBakeOptions::gpuResident): eq. 1 accumulated on the
// device, whose field refreshes the history's device grid; nothing comes back to the host.
void residentFrame(GpuMeshBaker& baker, RtsdfHistory& h, const GridShape& shape,
                   const MeshBakeOptions& o, GpuBakeTimes& t, StageClock& clock,
                   MeshBakeResult& r) {
    RtsdfOptions ro = o.rtsdf;
    ro.coarseSign = o.sign;
    RtsdfStats st;
    const float* field = baker.accumulateOnDevice(shape, ro, h.alpha, nullptr, &st, &t);
    h.frames = baker.accumulatedFrames();
    clock.mark("rtsdf (gpu)");
    GpuRefreshTimes rt;
    h.device->grid->refresh(field, &rt);
    clock.mark("refresh (gpu)");
    r.details = rtsdfDetails(st, ro.rays, baker, t,
                             "grid refresh " + millis(rt.blocksMs + rt.skipMs) + "; frame " +
                                 std::to_string(h.frames) +
                                 " accumulated and its grid refreshed on the GPU");
    r.onDevice = true;
}

// The frame's samples on the GPU, brought to the host: RTSDF's (a frame of a history, or a single
// bake) or jump flooding's.
std::vector<float> hostSamples(GpuMeshBaker& baker, RtsdfHistory* h, bool onDevice,
                               const GridShape& shape, const MeshBakeOptions& o, GpuBakeTimes& t,
                               StageClock& clock, MeshBakeResult& r) {
    std::vector<float> samples;
    if (o.method == MeshBakeMethod::Rtsdf) {
        RtsdfOptions ro = o.rtsdf;
        ro.coarseSign = o.sign;
        RtsdfStats st;
        if (h) {
            samples = baker.accumulate(shape, ro, h->alpha, onDevice ? nullptr : h, &st, &t);
            h->shape = shape;
            h->fine.clear();
            h->frames = baker.accumulatedFrames();
        } else {
            samples = baker.rtsdf(shape, ro, &st, &t);
        }
        clock.mark("rtsdf (gpu)");
        const std::string frame =
            h ? "; frame " + std::to_string(h->frames) + " accumulated on the GPU" : "";
        r.details = rtsdfDetails(st, ro.rays, baker, t, "relax " + millis(t.relaxMs) + frame);
        return samples;
    }
    samples = baker.jumpFlood(shape, o.jfaVariant, o.sign, o.betaVoxels, &t);
    clock.mark("jump flooding (gpu)");
    std::string passes;
    for (size_t i = 0; i < t.passMs.size(); ++i) passes += (i ? ", " : "") + millis(t.passMs[i]);
    r.details = std::to_string(t.passMs.size()) + " passes on the GPU (" + passes + "); seeds " +
                millis(t.seedMs) + ", signs " + millis(t.signMs) + " (" + signMethodName(o.sign) +
                ", every vertex)";
    return samples;
}

}  // namespace

MeshBakeResult bakeMeshGpu(const TriangleMesh& mesh, const MeshBakeOptions& o) {
    checkMeshBake(mesh, o);
    if (std::string why = gpuBakeUnsupported(o); !why.empty())
        throw InputError("--device cuda: " + why);
    const SampleOptions& so = o.sampling;
    const GridShape shape = o.shape ? *o.shape : gridShapeFor(mesh.bounds(), so);
    MeshBakeResult r;
    StageClock clock(r.stages);
    // An rtsdf bake with a history is a frame of RTSDF's per-frame regeneration (§2.5): its baker
    // and f_{t-1} stay on the device in the history, and the next frame poses the mesh there.
    // Where the CPU accumulated last (the host holds f_{t-1}), the GPU continues from the host's.
    RtsdfHistory* h = o.method == MeshBakeMethod::Rtsdf ? o.rtsdf.history : nullptr;
    const bool onDevice = h && h->device && h->frames > 0 && h->fine.empty();
    GpuBakeTimes t;
    std::optional<GpuMeshBaker> own;
    if (h && h->device) {
        h->device->baker.pose(mesh, &t);
        clock.mark("pose (gpu)");
    } else if (h) {
        // Signs by the dipoles over the LBVH: no host work when the mesh is posed.
        h->device = std::make_shared<RtsdfDeviceState>(
            RtsdfDeviceState{GpuMeshBaker(mesh, GpuWinding::Lbvh), std::nullopt});
        clock.mark("upload + lbvh (gpu)");
    } else {
        own.emplace(mesh);
        clock.mark("upload + lbvh (gpu)");
    }
    GpuMeshBaker& baker = h ? h->device->baker : *own;
    if (h && o.gpuResident && onDevice && h->device->grid && h->grid &&
        sameCompleteLayout(*h->grid, shape, so)) {
        residentFrame(baker, *h, shape, o, t, clock, r);
        return r;
    }
    finishMeshBake(shape, hostSamples(baker, h, onDevice, shape, o, t, clock, r), so, r, clock, h);
    // The device grid the next frames refresh, uploaded once from this frame's.
    if (h && o.gpuResident && r.grid.isComplete()) {
        h->device->grid.emplace(r.grid);
        clock.mark("grid upload (gpu)");
    }
    return r;
}

}  // namespace sdft
