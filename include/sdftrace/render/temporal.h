// Temporal accumulation of jittered frames (RTSDF §2.5.2: jittered soft shadows, then TAA after
// Karis 2014). Each frame moves the camera by a subpixel Halton (2, 3) offset and reseeds the
// per-pixel jitter of soft shadows and light samples; frames are blended into a history:
//  - stills (no camera motion): a running mean, so k frames average k jittered samples per pixel;
//  - animations (the camera orbits its target by `orbitDegrees` per frame): the history is
//    reprojected through the current frame's depth into the previous camera, clamped to the
//    current frame's 3 x 3 colour neighbourhood (against ghosting), and blended with weight alpha.
#pragma once

#include <functional>

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

// Renders the frames into `film`: colour is the accumulated image, the other AOVs those of the last
// frame. `onFrame(k, film)`, if set, sees each accumulated frame. Stats are summed over frames.
RenderStats renderFrames(const RenderPlan& plan, Film& film, const TemporalOptions& options,
                         const std::function<void(int, const Film&)>& onFrame = nullptr,
                         bool progress = false);

}  // namespace sdft
