// Compiled only where CMake finds a CUDA compiler: proves that the header-only code a CUDA backend
// will share (primitives, CSG operators, domain transforms, noise, the sphere-tracing state
// machine) compiles as device code. Not linked into anything; there is no GPU backend yet.
#include "sdftrace/field/noise.h"
#include "sdftrace/field/operators.h"
#include "sdftrace/field/primitives.h"
#include "sdftrace/field/transforms.h"
#include "sdftrace/trace/sphere_tracer.h"

namespace sdft {

// One thread per ray, tracing a displaced smooth union of a sphere and a torus.
__global__ void traceDeviceCheck(const Ray* rays, TraceOptions options, float* depth, int count) {
    int i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= count) return;
    const float sphereParams[1] = {1.0f};
    const float torusParams[2] = {1.2f, 0.2f};
    Bounds3 bounds{Vec3(-2.0f), Vec3(2.0f)};
    SphereTraceState state;
    sphereTraceBegin(state, rays[i], 0.0f, 100.0f, bounds, options);
    while (!state.done()) {
        Vec3 p = state.queryPoint();
        float h;
        float f =
            ops::smoothMin(prim::sphere(p, sphereParams), prim::torus(p, torusParams), 0.2f, h);
        f += 0.02f * noise::fbm(p * 3.0f, 2, 0.5f);
        sphereTraceAdvance(state, f, 1.0f / 1.5f, options);
    }
    depth[i] = state.result.t;
}

}  // namespace sdft
