#include "sdftrace/view/viewer_session.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "sdftrace/core/error.h"
#include "sdftrace/io/atomic_file.h"
#include "sdftrace/io/image_io.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/plan_render.h"
#include "sdftrace/scene/render_options.h"

namespace sdft {

namespace {

// The scene's camera with the size and the camera flags applied.
CameraDesc startCamera(const Scene& scene, const ViewerOptions& o) {
    CameraDesc c = scene.camera;
    if (o.eye) c.eye = *o.eye;
    if (o.target) c.target = *o.target;
    if (o.up) c.up = *o.up;
    if (o.fov) c.fovDeg = *o.fov;
    if (o.width) c.width = *o.width;
    if (o.height) c.height = *o.height;
    return c;
}

// A shell word: as is when it needs no quotes, else in single quotes.
std::string shellWord(const std::string& s) {
    if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                          "0123456789_-./=,:+@%") == std::string::npos)
        return s;
    std::string q = "'";
    for (char ch : s) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
    return q + "'";
}

}  // namespace

ViewerSession::ViewerSession(const ViewerOptions& options)
    : m_source(options.input),
      m_camera(startCamera(m_source.scene(), options)),
      m_view(options.progressive),
      m_threads(options.threads) {
    m_camera.setHome(startCamera(m_source.scene(), options));
    replan();
}

void ViewerSession::replan() {
    Scene scene = m_source.scene();
    if (m_classic) scene.settings.trace = TraceOptions::classic();
    for (const auto& [key, value] : m_overrides) findRenderOption(key)->give(scene.settings, value);
    if (m_threads > 0) scene.settings.threads = m_threads;
    scene.camera = m_camera.camera();
    m_settings = scene.settings;
    m_view.setPlan(planRender(scene));
    m_view.setCamera(m_camera.camera());
}

void ViewerSession::cameraMoved() { m_view.setCamera(m_camera.camera()); }

void ViewerSession::orbit(float dx, float dy) {
    m_camera.orbit(dx, dy);
    cameraMoved();
}

void ViewerSession::pan(float dx, float dy) {
    m_camera.pan(dx, dy);
    cameraMoved();
}

void ViewerSession::zoom(float clicks) {
    m_camera.zoom(clicks);
    cameraMoved();
}

void ViewerSession::fly(float forward, float right, float up) {
    m_camera.fly(forward, right, up);
    cameraMoved();
}

void ViewerSession::resetView() {
    m_camera.reset();
    cameraMoved();
}

void ViewerSession::resize(int width, int height) {
    validateImageSize(width, height, "the window size");
    if (width == camera().width && height == camera().height) return;
    m_camera.setSize(width, height);
    cameraMoved();
}

void ViewerSession::setOption(const std::string& key, double value) {
    const RenderOption* o = findRenderOption(key);
    if (!o) throw InputError("set " + key + ": unknown render option");
    if (o->type == OptionType::Int || o->type == OptionType::Float) {
        if (std::string e = o->check(value); !e.empty()) throw InputError("set " + key + ": " + e);
    } else if (value < 0 || (o->type == OptionType::Bool && value > 1) ||
               (o->type == OptionType::Choice && value >= static_cast<double>(o->choices.size()))) {
        throw InputError("set " + key + ": expected " + o->accepted());
    }
    m_overrides[key] = value;
    replan();
}

void ViewerSession::setClassic(bool classic) {
    m_classic = classic;
    replan();
}

void ViewerSession::setFrames(int frames) { m_view.setFrames(frames); }

bool ViewerSession::pollInput() {
    const SceneSource::Poll p = m_source.poll();
    if (p == SceneSource::Poll::Unchanged) return false;
    if (p == SceneSource::Poll::Reloaded) replan();
    return true;
}

bool ViewerSession::reload() {
    const bool ok = m_source.reload() != SceneSource::Poll::Failed;
    if (ok) replan();
    return ok;
}

bool ViewerSession::step() {
    if (m_view.done()) return false;
    m_stats = m_view.step();
    m_lastPreview = m_view.showingPreview();
    return true;
}

std::vector<uint8_t> ViewerSession::picture(int& width, int& height, float range[2]) const {
    const Film& film = m_view.film();
    width = film.width;
    height = film.height;
    range[0] = range[1] = 0;
    if (m_aov != Aov::Color && m_aov != Aov::Normal) {
        bool any = false;
        for (float v : film.channel(m_aov)) {
            if (!std::isfinite(v)) continue;
            range[0] = any ? std::min(range[0], v) : v;
            range[1] = any ? std::max(range[1], v) : v;
            any = true;
        }
    }
    return aovPicture(film, m_aov, false, height);
}

void ViewerSession::screenshot(const std::string& path) const {
    imageFormatFromPath(path, "screenshot");
    checkWritablePath(path, "screenshot");
    if (m_view.film().pixels() == 0) throw InputError("screenshot: nothing rendered yet");
    writeAov(m_view.film(), m_aov, path);
}

std::string ViewerSession::renderCommand() const {
    std::string cmd = "sdftrace render";
    if (!input().empty()) cmd += " " + shellWord(input());
    cmd += " " + m_camera.cliFlags();
    if (m_classic) cmd += " --classic";
    for (const auto& [key, value] : m_overrides) {
        const RenderOption* o = findRenderOption(key);
        if (o->type == OptionType::Bool) {
            cmd += value != 0 ? " " + o->mainFlag() : " --no-" + o->mainFlag().substr(2);
            continue;
        }
        char buf[64];
        if (o->type == OptionType::Float)
            std::snprintf(buf, sizeof buf, "%.9g", value);
        else
            std::snprintf(buf, sizeof buf, "%s", o->show(value).c_str());
        cmd += " " + o->mainFlag() + " " + buf;
    }
    if (m_threads > 0) cmd += " --threads " + std::to_string(m_threads);
    cmd += " --frames " + std::to_string(frames()) + " -o view.png";
    if (m_aov != Aov::Color)
        cmd += std::string(" --aov ") + aovName(m_aov) + "=view_" + aovName(m_aov) + ".png";
    return cmd;
}

bool ViewerSession::run(const ViewCommand& c, bool& quit, std::string& out) {
    const std::string& n = c.name;
    auto num = [&](size_t i) { return static_cast<float>(c.numbers.at(i)); };
    if (n == "orbit")
        orbit(num(0), num(1));
    else if (n == "pan")
        pan(num(0), num(1));
    else if (n == "zoom")
        zoom(num(0));
    else if (n == "fly")
        fly(num(0), num(1), num(2));
    else if (n == "reset")
        resetView();
    else if (n == "set")
        setOption(c.args[0], c.numbers.at(0));
    else if (n == "tracer")
        setClassic(c.args[0] == "classic");
    else if (n == "aov") {
        Aov aov = Aov::Color;
        parseAov(c.args[0], aov);
        setAov(aov);
    } else if (n == "frames")
        setFrames(static_cast<int>(c.numbers.at(0)));
    else if (n == "wait")
        return refined();
    else if (n == "screenshot")
        screenshot(c.args[0]);
    else if (n == "command")
        out = renderCommand();
    else if (n == "reload")
        reload();
    else if (n == "quit")
        quit = true;
    // grab: the window's own (apps/sdftrace/viewer/viewer_window.cpp)
    return true;
}

}  // namespace sdft
