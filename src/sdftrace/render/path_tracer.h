// A progressive path tracer over the same scenes (Keinert et al. 2014, fig. 1 right; Kajiya 1986):
// unidirectional paths from the camera with
//  - next-event estimation at every non-specular vertex: one sampled point of each light and a
//    shadow ray (lights are not geometry: only next-event estimation reaches them, so mirrors and
//    glass do not show them);
//  - BSDFs: plastic is Lambertian diffuse (albedo colour x diffuse) plus a GGX microfacet lobe
//    (weight `specular`, alpha = roughness or sqrt(2 / (shininess + 2)), Schlick F0 = 0.04),
//    sampled by one-sample mixture of a cosine lobe and the GGX normal distribution; mirrors
//    reflect; dielectrics reflect or refract by Fresnel, absorbing inside (Beer-Lambert);
//  - an environment of constant radiance (Lighting::environment) for escaping rays;
//  - Russian roulette after three bounces.
// A light's intensity means the same as for the direct integrator: a white Lambertian surface
// facing a point light of intensity I at distance d has radiance I / d^2. With one bounce
// (max depth 1), no environment and no ambient, the estimate's mean is the direct integrator's
// image with distributed shadows (tested).
#pragma once

#include "sdftrace/render/renderer.h"

namespace sdft {

// Renders plan.settings.samplesPerPixel paths per pixel as seen by `view` into `film` (colour;
// depth, normal and steps of the first sample). Stats: primary rays are paths, secondary rays
// every further ray.
RenderStats renderPaths(const RenderPlan& plan, const FrameView& view, Film& film,
                        bool progress = false);

// The path tracer of one frame, a pixel rectangle at a time (FrameRenderer).
class PathFrame {
  public:
    PathFrame(const RenderPlan& plan, const FrameView& view, Film& film);
    ~PathFrame();
    // The pixels of `r`, serially; counters added to `st`.
    void render(const PixelRect& r, RenderStats& st) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace sdft
