// Everything `sdftrace view` does except the window (docs/viewer.md): the watched input, the
// camera controller, the render settings the panel switches (kept across reloads), the AOV shown,
// the progressive renderer, screenshots, the reproducing command and the script. The window
// (apps/sdftrace/viewer_window.cpp) only forwards input, uploads pictures and draws the panel, so
// that all of this is tested without a display.
#pragma once
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "sdftrace/render/film.h"
#include "sdftrace/render/render_stats.h"
#include "sdftrace/view/orbit_camera.h"
#include "sdftrace/view/progressive_view.h"
#include "sdftrace/view/scene_source.h"
#include "sdftrace/view/view_script.h"

namespace sdft {

struct ViewerOptions {
    std::string input;  // scene, mesh or grid file; "" = the demo
    std::optional<int> width, height;
    // Flags that override the scene's camera.
    std::optional<Vec3> eye, target, up;
    std::optional<float> fov;
    ProgressiveOptions progressive;
    int threads = 0;
};

class ViewerSession {
  public:
    explicit ViewerSession(const ViewerOptions& options);  // throws InputError on a bad input

    // Input from the window (pixels, wheel clicks, world units).
    void orbit(float dx, float dy);
    void pan(float dx, float dy);
    void zoom(float clicks);
    void fly(float forward, float right, float up);
    void resetView();
    void resize(int width, int height);
    float flySpeed() const { return m_camera.flySpeed(); }

    // The panel's switches. Options are set by their scene keys (render_options.h) and kept
    // across reloads; `classic` starts from plain sphere tracing, as render --classic.
    const RenderSettings& settings() const { return m_settings; }
    void setOption(const std::string& key, double value);
    void setClassic(bool classic);
    bool classic() const { return m_classic; }
    void setFrames(int frames);
    int frames() const { return m_view.frames(); }
    int previewDivisor() const { return m_view.options().previewDivisor; }
    void setAov(Aov aov) { m_aov = aov; }
    Aov aov() const { return m_aov; }

    // Once per loop: reloads the input if it changed on disk (true when it did, or failed: see
    // error()).
    bool pollInput();
    bool reload();
    // Renders the next pass when there is one; true when the picture changed.
    bool step();
    bool refined() const { return m_view.done(); }

    // The AOV shown as 8-bit RGB at the film's size (colour tone-mapped, normals as colours,
    // the others as heat maps over their range, without a legend); the range in `range`.
    std::vector<uint8_t> picture(int& width, int& height, float range[2]) const;
    // Writes the AOV shown of the full-resolution film as `render --aov` writes it.
    void screenshot(const std::string& path) const;
    // `sdftrace render <input> <camera> <switches> --frames N`: reproduces the refined view.
    std::string renderCommand() const;
    const CameraDesc& camera() const { return m_camera.camera(); }

    const std::string& error() const { return m_source.error(); }
    const std::string& input() const { return m_source.input(); }
    const RenderStats& lastStats() const { return m_stats; }
    bool lastWasPreview() const { return m_lastPreview; }
    int framesDone() const { return m_view.framesDone(); }
    int loads() const { return m_source.loads(); }

    // Runs one script command. Returns false while it must wait (`wait` before the picture is
    // refined): call again after the next step. Sets `quit` for quit; `out` gets `command`'s line.
    bool run(const ViewCommand& command, bool& quit, std::string& out);

  private:
    void replan();  // the scene with the switches applied, planned again
    void cameraMoved();

    SceneSource m_source;
    OrbitCamera m_camera;
    ProgressiveView m_view;
    RenderSettings m_settings;
    std::map<std::string, double> m_overrides;  // option key -> value, in the table's units
    bool m_classic = false;
    int m_threads = 0;
    Aov m_aov = Aov::Color;
    RenderStats m_stats;
    bool m_lastPreview = false;
};

}  // namespace sdft
