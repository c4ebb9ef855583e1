#include "sdftrace/view/progressive_view.h"

#include <algorithm>

#include "sdftrace/render/renderer.h"

namespace sdft {

void ProgressiveView::setPlan(RenderPlan plan) {
    const std::optional<CameraDesc> camera =
        m_plan ? std::optional<CameraDesc>(m_plan->camera) : std::nullopt;
    m_render = nullptr;  // the last plan's renderer refers to it: gone first
    m_plan.emplace(std::move(plan));
    if (camera) setCamera(*camera);
    // The renderer refers to the plan, which stays in place until the next setPlan.
    if (m_options.renderer) m_render = m_options.renderer(*m_plan);
    restart();
}

RenderStats ProgressiveView::renderPass(const FrameView& view, Film& film) const {
    return m_render ? m_render(view, film, false) : render(*m_plan, view, film);
}

void ProgressiveView::setCamera(const CameraDesc& camera) {
    if (!m_plan) return;
    m_plan->camera = camera;
    // Zoomed out past the plan's camera, rays still reach the scene's far side.
    m_plan->settings.maxDistance =
        resolveMaxDistance(m_plan->settings, camera, m_plan->sceneBounds);
    restart();
}

void ProgressiveView::setFrames(int frames) {
    m_options.frames = std::max(1, frames);
    restart();
}

void ProgressiveView::restart() {
    m_previewDone = false;
    m_framesDone = 0;
    m_history.reset();
}

bool ProgressiveView::done() const { return !m_plan || m_framesDone >= m_options.frames; }

RenderStats ProgressiveView::step() {
    if (done()) return {};
    const CameraDesc& cam = m_plan->camera;
    const int d = std::max(1, m_options.previewDivisor);
    if (!m_previewDone && d > 1) {
        // The preview: the same camera at 1/d of the pixels, no jitter.
        FrameView view{cam};
        view.camera.width = std::max(1, cam.width / d);
        view.camera.height = std::max(1, cam.height / d);
        m_preview.emplace(view.camera.width, view.camera.height);
        m_previewDone = true;
        return renderPass(view, *m_preview);
    }
    m_previewDone = true;
    // Frame k as renderFrames renders it, blended into a running mean.
    const FrameView view = accumulationFrame(cam, m_framesDone, m_options.frames);
    Film current(cam.width, cam.height);
    const RenderStats stats = renderPass(view, current);
    if (!m_history) m_history.emplace(0.0f, false);
    m_history->add(current);
    m_film = std::move(current);
    ++m_framesDone;
    return stats;
}

const Film& ProgressiveView::film() const {
    static const Film kNothing(0, 0);  // before the first pass
    if (m_framesDone > 0 && m_film) return *m_film;
    return m_preview ? *m_preview : kNothing;
}

}  // namespace sdft
