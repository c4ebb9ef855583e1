#include "sdftrace/render/temporal.h"

#include <algorithm>
#include <cmath>

#include "sdftrace/core/memory_budget.h"
#include "sdftrace/math/sampling.h"

namespace sdft {

namespace {

// Bilinear colour of `img` (3 channels, w x h) at continuous pixel coordinates (centres at +0.5).
Vec3 bilinear(const std::vector<float>& img, int w, int h, float px, float py) {
    const float fx = px - 0.5f, fy = py - 0.5f;
    const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
    const float ax = fx - x0, ay = fy - y0;
    Vec3 c(0.0f);
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            const int x = std::clamp(x0 + dx, 0, w - 1), y = std::clamp(y0 + dy, 0, h - 1);
            const float wgt = (dx ? ax : 1 - ax) * (dy ? ay : 1 - ay);
            const size_t p = 3 * (static_cast<size_t>(y) * w + x);
            c += Vec3(img[p], img[p + 1], img[p + 2]) * wgt;
        }
    return c;
}

}  // namespace

CameraDesc orbitCamera(const CameraDesc& c, float degrees) {
    CameraDesc out = c;
    const float a = radians(degrees);
    const Vec3 axis = normalize(c.up);
    const Vec3 v = c.eye - c.target;
    // Rodrigues' rotation of the eye about the up axis through the target.
    const Vec3 r =
        v * std::cos(a) + cross(axis, v) * std::sin(a) + axis * (dot(axis, v) * (1 - std::cos(a)));
    out.eye = c.target + r;
    return out;
}

RenderStats renderFrames(const RenderPlan& plan, Film& film, const TemporalOptions& o,
                         const std::function<void(int, const Film&)>& onFrame, bool progress) {
    const int w = film.width, h = film.height;
    const bool moving = o.orbitDegrees != 0;
    const float alpha = o.alpha > 0 ? o.alpha : (moving ? 0.9f : 0.0f);
    RenderStats total;
    // A frame's film besides the output film, and the colour history and its reprojection.
    checkMemoryBudget(Film::bytesNeeded(w, h) + 2.0 * 3 * sizeof(float) * w * h, "--frames",
                      "temporal accumulation of " + std::to_string(w) + "x" + std::to_string(h) +
                          " frames (a second film and the colour history)",
                      "render a smaller image");
    std::vector<float> history;
    Camera previous(plan.camera);
    for (int k = 0; k < std::max(1, o.frames); ++k) {
        FrameView s;
        s.camera = orbitCamera(plan.camera, o.orbitDegrees * static_cast<float>(k));
        s.frame = static_cast<uint32_t>(k);
        if (o.jitterCamera && o.frames > 1) {
            s.pixelJitter[0] = radicalInverse(static_cast<uint32_t>(k) + 1, 2) - 0.5f;
            s.pixelJitter[1] = radicalInverse(static_cast<uint32_t>(k) + 1, 3) - 0.5f;
        }
        Film current(w, h);
        const RenderStats frameStats = render(plan, s, current, progress && k == 0);
        total.add(frameStats);
        total.seconds += frameStats.seconds;
        total.threads = frameStats.threads;
        total.gridTracer = frameStats.gridTracer;
        const Camera camera(s.camera);
        if (k == 0) {
            history = current.color;
        } else {
            std::vector<float> next(current.color.size());
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const size_t i = static_cast<size_t>(y) * w + x;
                    const Vec3 cur(current.color[3 * i], current.color[3 * i + 1],
                                   current.color[3 * i + 2]);
                    Vec3 hist(history[3 * i], history[3 * i + 1], history[3 * i + 2]);
                    float weight = alpha > 0 ? alpha : static_cast<float>(k) / (k + 1);
                    if (moving) {
                        // Reproject through this frame's depth; clamp to the neighbourhood.
                        float px = x + 0.5f, py = y + 0.5f;
                        if (std::isfinite(current.depth[i])) {
                            const Vec3 p = camera
                                               .rayThrough(x + 0.5f + s.pixelJitter[0],
                                                           y + 0.5f + s.pixelJitter[1])
                                               .at(current.depth[i]);
                            if (!previous.project(p, px, py) || px < 0 || py < 0 || px >= w ||
                                py >= h)
                                weight = 0;  // newly visible: no history
                        }
                        hist = bilinear(history, w, h, px, py);
                        Vec3 lo(INFINITY), hi(-INFINITY);
                        for (int dy = -1; dy <= 1; ++dy)
                            for (int dx = -1; dx <= 1; ++dx) {
                                const int xx = std::clamp(x + dx, 0, w - 1),
                                          yy = std::clamp(y + dy, 0, h - 1);
                                const size_t j = 3 * (static_cast<size_t>(yy) * w + xx);
                                const Vec3 c(current.color[j], current.color[j + 1],
                                             current.color[j + 2]);
                                lo = min(lo, c);
                                hi = max(hi, c);
                            }
                        hist = min(max(hist, lo), hi);
                    }
                    const Vec3 out = hist * weight + cur * (1 - weight);
                    for (int c = 0; c < 3; ++c) next[3 * i + c] = out[c];
                }
            history.swap(next);
        }
        previous = camera;
        current.color = history;
        film = std::move(current);
        if (onFrame) onFrame(k, film);
    }
    return total;
}

}  // namespace sdft
