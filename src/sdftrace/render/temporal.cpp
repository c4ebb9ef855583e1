#include "sdftrace/render/temporal.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "sdftrace/core/macros.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/math/sampling.h"

namespace sdft {

namespace {

// Relative depth difference below which a history pixel shows the same surface.
constexpr float kDepthTolerance = 0.05f;

Vec3 rgbAt(const std::vector<float>& img, size_t i) {
    return {img[3 * i], img[3 * i + 1], img[3 * i + 2]};
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

void frameJitter(uint32_t k, float out[2]) {
    out[0] = radicalInverse(k + 1, 2) - 0.5f;
    out[1] = radicalInverse(k + 1, 3) - 0.5f;
}

TemporalAccumulator::TemporalAccumulator(float alpha, bool reproject, bool clamp, bool reject)
    : m_alpha(alpha > 0 ? alpha : (reproject ? 0.9f : 0.0f)),
      m_reproject(reproject),
      m_clamp(clamp),
      m_reject(reject) {}

namespace {

// The neighbourhood clamp (Karis 2014): `hist` within the box of the current 3 x 3 colours.
Vec3 clampToNeighbourhood(const Film& film, int x, int y, Vec3 hist) {
    const int w = film.width, h = film.height;
    Vec3 lo(INFINITY), hi(-INFINITY);
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
            const int xx = std::clamp(x + dx, 0, w - 1), yy = std::clamp(y + dy, 0, h - 1);
            const Vec3 c = rgbAt(film.color, static_cast<size_t>(yy) * w + xx);
            lo = min(lo, c);
            hi = max(hi, c);
        }
    return min(max(hist, lo), hi);
}

}  // namespace

bool TemporalAccumulator::reprojectedHistory(const Film& film, const MotionVectors& mv, int x,
                                             int y, bool shadowTest, Vec3& hist) const {
    const int w = film.width, h = film.height;
    const size_t i = static_cast<size_t>(y) * w + x;
    const float px = x + 0.5f + mv.motion[2 * i], py = y + 0.5f + mv.motion[2 * i + 1];
    if (!mv.visibleBefore[i] || px < 0 || py < 0 || px >= w || py >= h) return false;
    // Bilinear over the taps that show this surface: the same object at the distance the point
    // had from the previous eye (and, with the shadow test, as visible a light).
    const float fx = px - 0.5f, fy = py - 0.5f;
    const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
    const float ax = fx - x0, ay = fy - y0;
    const int object = mv.objects[i];
    const float d = mv.depthBefore[i];
    Vec3 sum(0.0f);
    float total = 0;
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            const int xx = std::clamp(x0 + dx, 0, w - 1), yy = std::clamp(y0 + dy, 0, h - 1);
            const size_t j = static_cast<size_t>(yy) * w + xx;
            if (m_reject && m_objects[j] != object) continue;
            if (m_reject && object >= 0 && !(std::fabs(m_depth[j] - d) <= kDepthTolerance * d))
                continue;
            if (shadowTest && std::fabs(m_shadow[j] - film.shadow[i]) > m_shadowChange) continue;
            const float wgt = (dx ? ax : 1 - ax) * (dy ? ay : 1 - ay);
            sum += rgbAt(m_history, j) * wgt;
            total += wgt;
        }
    if (!(total > 1e-4f)) return false;
    hist = sum / total;
    return true;
}

void TemporalAccumulator::add(Film& film, const MotionVectors* mv) {
    const int w = film.width, h = film.height;
    const size_t n = film.pixels();
    SDFT_CHECK(!m_reproject || (mv && mv->motion.size() == 2 * n && film.has(Aov::Depth)));
    if (m_frames == 0 || w != m_width || h != m_height) {
        m_frames = 0;
        m_width = w;
        m_height = h;
        m_history.clear();
    }
    if (m_frames == 0) {
        m_history = film.color;
        m_rejected = 0;
    } else {
        std::vector<float> next(film.color.size());
        const bool shadowTest = m_reject && m_shadowChange > 0 && film.has(Aov::Shadow) &&
                                m_shadow.size() == film.pixels();
        std::atomic<size_t> rejected{0};
        const float weight0 = m_alpha > 0 ? m_alpha : static_cast<float>(m_frames) / (m_frames + 1);
        tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
            size_t rejectedHere = 0;
            for (int y = rows.begin(); y != rows.end(); ++y)
                for (int x = 0; x < w; ++x) {
                    const size_t i = static_cast<size_t>(y) * w + x;
                    Vec3 hist = rgbAt(m_history, i);
                    float weight = weight0;
                    if (m_reproject) {
                        if (!reprojectedHistory(film, *mv, x, y, shadowTest, hist)) {
                            weight = 0;
                            ++rejectedHere;
                        } else if (m_clamp) {
                            hist = clampToNeighbourhood(film, x, y, hist);
                        }
                    }
                    const Vec3 out = hist * weight + rgbAt(film.color, i) * (1 - weight);
                    for (int c = 0; c < 3; ++c) next[3 * i + c] = out[c];
                }
            rejected += rejectedHere;
        });
        m_history.swap(next);
        m_rejected = rejected;
    }
    if (m_reproject) {
        m_objects = mv->objects;
        m_depth = film.depth;
        if (m_shadowChange > 0 && film.has(Aov::Shadow)) m_shadow = film.shadow;
    }
    ++m_frames;
    film.color = m_history;
}

FrameView accumulationFrame(const CameraDesc& camera, int k, int frames, bool jitter) {
    FrameView view{camera};
    view.frame = static_cast<uint32_t>(k);
    if (jitter && frames > 1) frameJitter(static_cast<uint32_t>(k), view.pixelJitter);
    return view;
}

RenderStats renderFrames(const RenderPlan& plan, Film& film, const TemporalOptions& o,
                         const std::function<void(int, const Film&)>& onFrame, bool progress,
                         const FrameRenderFn& renderFrame) {
    const int w = film.width, h = film.height;
    const bool moving = o.orbitDegrees != 0;
    RenderStats total;
    // A frame's film besides the output film, the colour history (12 bytes a pixel) and, when
    // reprojecting, its objects and depths (8) and the frame's motion vectors (17).
    const double perPixel = moving ? 37.0 : 12.0;
    checkMemoryBudget(Film::bytesNeeded(w, h) + perPixel * w * h, "--frames",
                      "temporal accumulation of " + std::to_string(w) + "x" + std::to_string(h) +
                          " frames (a second film and the colour history)",
                      "render a smaller image");
    TemporalAccumulator history(o.alpha, moving);
    CameraDesc previous = plan.camera;
    for (int k = 0; k < std::max(1, o.frames); ++k) {
        const FrameView s =
            accumulationFrame(orbitCamera(plan.camera, o.orbitDegrees * static_cast<float>(k)), k,
                              o.frames, o.jitterCamera);
        Film current(w, h);
        const bool bar = progress && k == 0;
        const RenderStats frameStats =
            renderFrame ? renderFrame(s, current, bar) : render(plan, s, current, bar);
        total.add(frameStats);
        total.seconds += frameStats.seconds;
        total.threads = frameStats.threads;
        total.ranks = frameStats.ranks;
        total.gridTracer = frameStats.gridTracer;
        total.gpu = frameStats.gpu;
        total.gpuKernelMs += frameStats.gpuKernelMs;
        total.gpuFrameMs += frameStats.gpuFrameMs;
        if (moving) {
            const MotionVectors mv =
                motionVectors(current.depth, s.camera, s.pixelJitter, previous, nullptr);
            history.add(current, &mv);
        } else {
            history.add(current);
        }
        previous = s.camera;
        film = std::move(current);
        if (onFrame) onFrame(k, film);
    }
    return total;
}

}  // namespace sdft
