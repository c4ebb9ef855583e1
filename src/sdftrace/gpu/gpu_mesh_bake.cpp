// bakeMesh on the GPU (gpu_bake.h): what the GPU bakes, and the result assembled as the CPU's
// (stages, details, a sparse grid from the dense samples). Built with and without CUDA: without
// it, GpuMeshBaker answers with gpu_absent.cpp's one line.
#include <chrono>
#include <cstdio>

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

std::string millis(double ms) {
    char s[32];
    std::snprintf(s, sizeof s, "%.2f ms", ms);
    return s;
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
    GpuMeshBaker baker(mesh);
    clock.mark("upload + lbvh (gpu)");
    GpuBakeTimes t;
    std::vector<float> samples;
    if (o.method == MeshBakeMethod::Rtsdf) {
        RtsdfOptions ro = o.rtsdf;
        ro.coarseSign = o.sign;
        RtsdfStats st;
        samples = baker.rtsdf(shape, ro, &st, &t);
        clock.mark("rtsdf (gpu)");
        char line[400];
        std::snprintf(line, sizeof line,
                      "%zu vertices refined by %d rays each (%zu rays), %zu with no hit; GPU: "
                      "lbvh %s, seeds %s, jfa %s, signs %s, rays %s, relax %s",
                      st.refined, ro.rays, st.rays, st.missed, millis(baker.lbvhBuildMs()).c_str(),
                      millis(t.seedMs).c_str(), millis(t.jfaMs).c_str(), millis(t.signMs).c_str(),
                      millis(t.rayMs).c_str(), millis(t.relaxMs).c_str());
        r.details = line;
    } else {
        samples = baker.jumpFlood(shape, o.jfaVariant, o.sign, o.betaVoxels, &t);
        clock.mark("jump flooding (gpu)");
        std::string passes;
        for (size_t i = 0; i < t.passMs.size(); ++i)
            passes += (i ? ", " : "") + millis(t.passMs[i]);
        r.details = std::to_string(t.passMs.size()) + " passes on the GPU (" + passes +
                    "); seeds " + millis(t.seedMs) + ", signs " + millis(t.signMs) + " (" +
                    signMethodName(o.sign) + ", every vertex)";
    }
    finishMeshBake(shape, std::move(samples), so, r, clock);
    return r;
}

}  // namespace sdft
