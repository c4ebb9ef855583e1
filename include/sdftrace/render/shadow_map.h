// The shadow-map baseline RTSDF §3 compares SDF soft shadows with: a depth map seen from the light
// (here rendered by sphere tracing the field, one ray per texel), looked up per shading point and
// filtered by
//  - PCF, percentage-closer filtering (Reeves et al. 1987): the share of (2r+1)² depth tests that
//    pass around the point's texel;
//  - EVSM, exponential variance shadow maps (Lauritzen & McCool 2008): the moments of two
//    exponentially warped depths, box-filtered over (2r+1)² texels (RTSDF fig. 14 uses 15 x 15),
//    and Chebyshev's bound on the share of the filter footprint nearer the light than the point,
//    with light-bleeding reduction.
// Directional lights get an orthographic map fitted to the shadowed region, positional lights a
// cube map (six 90-degree perspective faces of resolution / 2) from their centre.
#pragma once

#include <cstdint>
#include <vector>

#include "sdftrace/field/tape.h"
#include "sdftrace/render/lighting.h"
#include "sdftrace/trace/trace_options.h"

namespace sdft {

enum class ShadowMapFilter { Pcf, Evsm };

struct ShadowMapOptions {
    int resolution = 1024;                      // texels along each side
    int pcfRadius = 2;                          // PCF: (2r+1)^2 taps
    int evsmRadius = 7;                         // EVSM: box filter of (2r+1)^2 texels
    float evsmPositive = 40, evsmNegative = 5;  // warp exponents
    float bleedReduction = 0.2f;                // EVSM: visibility below this becomes 0
    float bias = 1.5f;  // texels: lookups move this far along the normal, and compare this far
};

class ShadowMap {
  public:
    // Renders the map of `tape` from `light` over `region` (finite; where shading points lie),
    // on the calling task arena.
    ShadowMap(const Tape& tape, const Light& light, const Bounds3& region,
              const TraceOptions& trace, ShadowMapFilter filter, const ShadowMapOptions& options);

    // Visibility of the light at p (normal n): 1 lit, 0 in shadow; points outside the map are lit.
    float visibility(Vec3 p, Vec3 n) const;

    uint64_t evaluations() const { return m_evaluations; }

  private:
    struct Face {
        Vec3 forward, right, up;
    };
    // Map coordinates of p: its face, texel x, y (continuous, texel centres at +0.5), the depth
    // to compare and the world size of a texel there. False when p is outside the map.
    bool project(Vec3 p, int& face, float& x, float& y, float& depth, float& texel) const;
    float pcf(int face, float x, float y, float depth, float bias) const;
    float evsm(int face, float x, float y, float depth) const;
    // The map's faces and depth range; each returns the rays' t_max.
    float orthographicFaces(const Tape& tape, const Light& light, Vec3 centre, float radius);
    float cubeFaces(const Light& light, Vec3 centre, float radius);
    // One sphere-traced ray per texel, in rows of texels.
    void traceDepths(const Tape& tape, const TraceOptions& trace, float tMax);
    // EVSM: the warped moments of the depths, box filtered within each face.
    void buildMoments();

    ShadowMapFilter m_filter;
    ShadowMapOptions m_o;
    bool m_ortho = true;
    Vec3 m_origin;  // ortho: the map plane's corner; cube: the light
    std::vector<Face> m_faces;
    float m_extent = 1;            // ortho: world size of the map
    float m_near = 0, m_far = 1;   // depth range for EVSM's normalization
    int m_res = 0;                 // texels along a face's side
    std::vector<float> m_depth;    // per face and texel: depth of the first hit, +inf if none
    std::vector<float> m_moments;  // EVSM: 4 per texel, filtered within each face
    uint64_t m_evaluations = 0;
};

}  // namespace sdft
