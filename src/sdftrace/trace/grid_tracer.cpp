#include "sdftrace/trace/grid_tracer.h"

#include "sdftrace/core/macros.h"
#include "sdftrace/exec/simd.h"
#include "sdftrace/trace/grid_dda.h"

namespace sdft {

namespace {

using grid_dda::gradientNormal;
using grid_dda::hitNormal;
using grid_dda::traceRay;
using grid_dda::traceShadow;

// Each entry point built for AVX2 and for the baseline (core/macros.h); exec/simd.h picks.
SDFT_TARGET_AVX2 GridTraceResult traceGridRayAvx2(const GridView& g, const Ray& ray, float tMin,
                                                  float tMax, const GridTraceOptions& o,
                                                  float startSign) {
    return traceRay(g, ray, tMin, tMax, o, startSign);
}
SDFT_TARGET_BASELINE GridTraceResult traceGridRayBaseline(const GridView& g, const Ray& ray,
                                                          float tMin, float tMax,
                                                          const GridTraceOptions& o,
                                                          float startSign) {
    return traceRay(g, ray, tMin, tMax, o, startSign);
}
SDFT_TARGET_AVX2 GridTraceResult traceGridShadowAvx2(const GridView& g, const Ray& ray, float tMin,
                                                     float tMax, const GridTraceOptions& o,
                                                     int threshold) {
    return traceShadow(g, ray, tMin, tMax, o, threshold);
}
SDFT_TARGET_BASELINE GridTraceResult traceGridShadowBaseline(const GridView& g, const Ray& ray,
                                                             float tMin, float tMax,
                                                             const GridTraceOptions& o,
                                                             int threshold) {
    return traceShadow(g, ray, tMin, tMax, o, threshold);
}
SDFT_TARGET_AVX2 Vec3 gridNormalAvx2(const GridView& g, Vec3 p, GridNormal method) {
    return gradientNormal(g, p, method);
}
SDFT_TARGET_BASELINE Vec3 gridNormalBaseline(const GridView& g, Vec3 p, GridNormal method) {
    return gradientNormal(g, p, method);
}
SDFT_TARGET_AVX2 Vec3 gridHitNormalAvx2(const GridView& g, const GridTraceResult& hit, Vec3 p,
                                        GridNormal method) {
    return hitNormal(g, hit, p, method);
}
SDFT_TARGET_BASELINE Vec3 gridHitNormalBaseline(const GridView& g, const GridTraceResult& hit,
                                                Vec3 p, GridNormal method) {
    return hitNormal(g, hit, p, method);
}

}  // namespace

GridTraceResult traceGridRay(const GridView& g, const Ray& ray, float tMin, float tMax,
                             const GridTraceOptions& o, float startSign) {
    return useAvx2() ? traceGridRayAvx2(g, ray, tMin, tMax, o, startSign)
                     : traceGridRayBaseline(g, ray, tMin, tMax, o, startSign);
}

float gridSignAt(const GridView& g, Vec3 p) { return grid_dda::signAt(g, p); }

GridTraceResult traceGridShadow(const GridView& g, const Ray& ray, float tMin, float tMax,
                                const GridTraceOptions& o, int threshold) {
    return useAvx2() ? traceGridShadowAvx2(g, ray, tMin, tMax, o, threshold)
                     : traceGridShadowBaseline(g, ray, tMin, tMax, o, threshold);
}

Vec3 gridNormal(const GridView& g, Vec3 p, GridNormal method) {
    return useAvx2() ? gridNormalAvx2(g, p, method) : gridNormalBaseline(g, p, method);
}

Vec3 gridHitNormal(const GridView& g, const GridTraceResult& hit, Vec3 p, GridNormal method) {
    return useAvx2() ? gridHitNormalAvx2(g, hit, p, method)
                     : gridHitNormalBaseline(g, hit, p, method);
}

}  // namespace sdft
