// Temporal accumulation of jittered frames (RTSDF §2.5.2: jittered soft shadows, then TAA after
// Karis 2014). Each frame moves the camera by a subpixel Halton (2, 3) offset and reseeds the
// per-pixel jitter of soft shadows and light samples; frames are blended into a history:
//  - stills (nothing moves): a running mean, so k frames average k jittered samples per pixel;
//  - moving cameras (`orbitDegrees` per frame) and animated scenes (issue 16): the history is
//    reprojected by each pixel's motion vector (motion.h: the camera's motion, and each object's
//    own from its placement at the two instants), rejected where the previous frame saw another
//    object or a surface at another depth there (disocclusion: the ground a moving object
//    uncovers) or, optionally, where the first light's visibility changed (moving shadows), clamped
//    to the current frame's 3 x 3 colour neighbourhood (shading, deforming objects), and blended
//    with weight alpha.
#pragma once

#include <functional>

#include "sdftrace/render/motion.h"
#include "sdftrace/render/renderer.h"

namespace sdft {

struct TemporalOptions {
    int frames = 1;
    float alpha = 0;  // history weight in [0, 1); 0: a running mean (stills), 0.9 when moving
    float orbitDegrees = 0;    // camera orbit about the target's up axis per frame
    bool jitterCamera = true;  // subpixel offsets (anti-aliasing)
};

// The camera of frame k: orbited by k * degrees about the vertical through the target.
CameraDesc orbitCamera(const CameraDesc& camera, float degrees);

// The subpixel offset of frame k, in [-0.5, 0.5)^2: Halton (2, 3) at index k + 1.
void frameJitter(uint32_t k, float out[2]);

// Frame k of `frames` accumulated still frames through `camera` (renderFrames, the viewer): its
// number seeds the per-pixel sequences, and it is jittered when more than one is accumulated.
FrameView accumulationFrame(const CameraDesc& camera, int k, int frames, bool jitter = true);

// The history of one sequence of frames of a fixed size.
class TemporalAccumulator {
  public:
    // alpha: the history's weight; 0 gives a running mean for stills and 0.9 when reprojecting.
    // `clamp` (the neighbourhood clamp) and `reject` (the object and depth tests) are switches
    // to measure each part against the others; both are on in every renderer.
    TemporalAccumulator(float alpha, bool reproject, bool clamp = true, bool reject = true);
    // Blends film.color with the history and makes it the blended image. Reprojecting needs the
    // frame's depth and motion vectors; stills pass none. A frame of another size restarts.
    void add(Film& film, const MotionVectors* motion = nullptr);
    // Also reject history where the first shadowing light's visibility (the shadow AOV, which
    // the films must then keep) changed by more than `change` since the previous frame: a moving
    // occluder's shadow, or a moving light's, leaves no trail on surfaces that do not move. Only
    // for deterministic shadows (hard, soft): stochastic ones vary from frame to frame by design.
    void rejectShadowChanges(float change) { m_shadowChange = change; }
    int frames() const { return m_frames; }
    int width() const { return m_width; }
    int height() const { return m_height; }
    // Pixels of the last frame whose history was discarded (disoccluded or off screen).
    size_t rejected() const { return m_rejected; }

  private:
    // The history at pixel (x, y) reprojected by its motion vector over the previous frame's
    // taps that pass the rejection tests; false when none does (no history there).
    bool reprojectedHistory(const Film& film, const MotionVectors& mv, int x, int y,
                            bool shadowTest, Vec3& hist) const;

    float m_alpha;
    bool m_reproject, m_clamp, m_reject;
    int m_frames = 0, m_width = 0, m_height = 0;
    size_t m_rejected = 0;
    std::vector<float> m_history;  // 3 per pixel
    std::vector<int> m_objects;    // what the history's pixels show (MotionVectors::objects)
    std::vector<float> m_depth;    // and at what distance
    std::vector<float> m_shadow;   // and how visible the first shadowing light was
    float m_shadowChange = 0;
};

// Renders the frames into `film`: colour is the accumulated image, the other AOVs those of the last
// frame. `onFrame(k, film)`, if set, sees each accumulated frame. Stats are summed over frames.
// `renderFrame`, when set, renders each frame instead of render(plan, ...) (a render across
// ranks, cluster/distributed_render.h).
using FrameRenderFn = std::function<RenderStats(const FrameView&, Film&, bool progress)>;
RenderStats renderFrames(const RenderPlan& plan, Film& film, const TemporalOptions& options,
                         const std::function<void(int, const Film&)>& onFrame = nullptr,
                         bool progress = false, const FrameRenderFn& renderFrame = nullptr);

}  // namespace sdft
