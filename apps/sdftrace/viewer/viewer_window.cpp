#include "viewer_window.h"

#define GLFW_INCLUDE_NONE
#include <GL/gl.h>
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl2.h>
#include <imgui.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "sdftrace/core/error.h"
#include "sdftrace/io/atomic_file.h"
#include "sdftrace/io/image_io.h"
#include "sdftrace/scene/render_options.h"

namespace sdft::cli {

namespace {

// Input that arrives through GLFW's callbacks (ImGui's backend chains to them).
struct Events {
    double scroll = 0;
    std::vector<int> keys;  // pressed this frame
};
Events* g_events = nullptr;
std::string g_glfwError;

void onScroll(GLFWwindow*, double, double dy) {
    if (g_events) g_events->scroll += dy;
}
void onKey(GLFWwindow*, int key, int, int action, int) {
    if (g_events && action == GLFW_PRESS) g_events->keys.push_back(key);
}

// The window and its GL texture; released on every way out.
struct Window {
    GLFWwindow* handle = nullptr;
    GLuint texture = 0;
    bool imgui = false;
    ~Window() {
        if (imgui) {
            ImGui_ImplOpenGL2_Shutdown();
            ImGui_ImplGlfw_Shutdown();
            ImGui::DestroyContext();
        }
        if (texture) glDeleteTextures(1, &texture);
        if (handle) glfwDestroyWindow(handle);
        glfwTerminate();
    }
};

std::string nextScreenshot(const std::string& dir) {
    for (int i = 0;; ++i) {
        char name[64];
        std::snprintf(name, sizeof name, "sdftrace-view-%04d.png", i);
        const std::string path = (std::filesystem::path(dir) / name).string();
        if (!std::filesystem::exists(path)) return path;
    }
}

const char* kAovs[] = {"color",      "depth",       "normal", "steps", "error",
                       "trav_steps", "isect_tests", "shadow", "ao"};

// One widget per render option of the table, grouped as the CLI's help groups them.
void optionWidgets(ViewerSession& s, std::string& message) {
    std::vector<std::string> groups;
    for (const RenderOption& o : renderOptions())
        if (std::find(groups.begin(), groups.end(), o.group) == groups.end())
            groups.push_back(o.group);
    for (const std::string& g : groups) {
        if (!ImGui::CollapsingHeader(g.c_str(), g == "Tracer" ? ImGuiTreeNodeFlags_DefaultOpen : 0))
            continue;
        for (const RenderOption& o : renderOptions()) {
            if (o.group != g) continue;
            const double v = o.get(s.settings());
            try {
                if (o.type == OptionType::Bool) {
                    bool b = v != 0;
                    if (ImGui::Checkbox(o.key, &b)) s.setOption(o.key, b ? 1 : 0);
                } else if (o.type == OptionType::Choice) {
                    int i = static_cast<int>(v);
                    if (ImGui::Combo(o.key, &i, o.choices.data(),
                                     static_cast<int>(o.choices.size())))
                        s.setOption(o.key, i);
                } else if (o.type == OptionType::Int) {
                    int i = static_cast<int>(v);
                    if (ImGui::InputInt(o.key, &i, 1, 10, ImGuiInputTextFlags_EnterReturnsTrue))
                        s.setOption(o.key, i);
                } else {
                    float f = static_cast<float>(v);
                    if (ImGui::InputFloat(o.key, &f, 0, 0, "%.6g",
                                          ImGuiInputTextFlags_EnterReturnsTrue))
                        s.setOption(o.key, f);
                }
            } catch (const InputError& e) {
                message = e.what();
            }
            if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", o.doc);
        }
    }
}

void panel(ViewerSession& s, const float range[2], int& frames, std::string& message,
           bool& screenshot, bool& printCommand) {
    ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(360, std::min(ImGui::GetIO().DisplaySize.y - 16, 640.0f)),
                             ImGuiCond_FirstUseEver);
    ImGui::Begin("sdftrace view");
    const RenderStats& st = s.lastStats();
    const double rays = std::max<double>(1, static_cast<double>(st.primaryRays));
    ImGui::Text("%s", s.input().empty() ? "<demo scene>" : s.input().c_str());
    ImGui::Text(
        "%s %dx%d: %.1f ms", s.lastWasPreview() ? "preview" : "frame",
        s.lastWasPreview() ? s.camera().width / std::max(1, s.previewDivisor()) : s.camera().width,
        s.lastWasPreview() ? s.camera().height / std::max(1, s.previewDivisor())
                           : s.camera().height,
        st.seconds * 1e3);
    ImGui::Text("%.2f Mrays/s, %.2f evaluations per ray", rays / std::max(st.seconds, 1e-9) * 1e-6,
                static_cast<double>(st.primaryEvaluations) / rays);
    ImGui::Text("refined: %d of %d frames", s.framesDone(), s.frames());
    if (s.aov() != Aov::Color && s.aov() != Aov::Normal) {
        ImGui::Text("%s: heat map from %.4g to %.4g", aovName(s.aov()), range[0], range[1]);
    }
    if (!s.error().empty()) {
        ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1, 0.4f, 0.4f, 1));
        ImGui::TextWrapped("reload failed, showing the last good scene: %s", s.error().c_str());
        ImGui::PopStyleColor();
    }
    if (!message.empty()) {
        ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1, 0.7f, 0.3f, 1));
        ImGui::TextWrapped("%s", message.c_str());
        ImGui::PopStyleColor();
    }
    int aov = static_cast<int>(s.aov());
    if (ImGui::Combo("AOV", &aov, kAovs, IM_ARRAYSIZE(kAovs))) s.setAov(static_cast<Aov>(aov));
    bool classic = s.classic();
    if (ImGui::Checkbox("classic sphere tracing (--classic)", &classic)) s.setClassic(classic);
    if (ImGui::SliderInt("frames", &frames, 1, 64)) s.setFrames(frames);
    optionWidgets(s, message);
    if (ImGui::Button("Reset view (R)")) s.resetView();
    ImGui::SameLine();
    if (ImGui::Button("Print command (P)")) printCommand = true;
    ImGui::SameLine();
    if (ImGui::Button("Screenshot (F12)")) screenshot = true;
    ImGui::TextWrapped("%s", s.renderCommand().c_str());
    ImGui::End();
}

// The back buffer as drawn (rows bottom to top in GL) to an image file.
void grabWindow(int w, int h, const std::string& path) {
    std::vector<unsigned char> rgb(static_cast<size_t>(w) * h * 3), flipped(rgb.size());
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_BACK);
    glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
    const size_t row = static_cast<size_t>(w) * 3;
    for (int y = 0; y < h; ++y)
        std::copy_n(rgb.data() + static_cast<size_t>(h - 1 - y) * row, row,
                    flipped.data() + static_cast<size_t>(y) * row);
    writePng(path, w, h, 3, flipped);
}

// Opens the window, the GL context, ImGui and the picture's texture (into `win`).
void openWindow(Window& win, const ViewerSession& s, Events& events) {
    glfwSetErrorCallback([](int, const char* text) { g_glfwError = text ? text : ""; });
    if (!glfwInit())
        throw InputError("view: cannot open a window (" + g_glfwError +
                         "); the viewer needs a display: run it in a desktop session, or "
                         "under xvfb-run");
    win.handle = glfwCreateWindow(
        s.camera().width, s.camera().height,
        ("sdftrace view - " + (s.input().empty() ? std::string("demo") : s.input())).c_str(),
        nullptr, nullptr);
    if (!win.handle) throw InputError("view: cannot create an OpenGL window (" + g_glfwError + ")");
    glfwMakeContextCurrent(win.handle);
    glfwSwapInterval(1);
    g_events = &events;
    // Set before ImGui's backend, which chains to them.
    glfwSetScrollCallback(win.handle, onScroll);
    glfwSetKeyCallback(win.handle, onKey);
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    win.imgui = true;
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini in the user's directory
    ImGui_ImplGlfw_InitForOpenGL(win.handle, true);
    ImGui_ImplOpenGL2_Init();
    glGenTextures(1, &win.texture);
    glBindTexture(GL_TEXTURE_2D, win.texture);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
}

// One pass of the main loop at a time: input, the script, the file watcher, a render pass,
// drawing.
class ViewerLoop {
  public:
    ViewerLoop(ViewerSession& s, const WindowOptions& o, Window& win, Events& events)
        : m_s(s),
          m_o(o),
          m_win(win),
          m_events(events),
          m_showPanel(o.panel),
          m_shown(s.aov()),
          m_frames(s.frames()) {
        m_lastPoll = m_lastTime = glfwGetTime();
        glfwGetCursorPos(win.handle, &m_mouseX, &m_mouseY);
    }

    bool running() const { return !m_quit && !glfwWindowShouldClose(m_win.handle); }

    void pass() {
        if (m_s.refined() && m_next >= m_o.script.size())
            glfwWaitEventsTimeout(0.25);  // still: wake for input or the file watcher
        else
            glfwPollEvents();
        const double now = glfwGetTime(), dt = std::min(0.1, now - m_lastTime);
        m_lastTime = now;
        int fbw = 0, fbh = 0;
        glfwGetFramebufferSize(m_win.handle, &fbw, &fbh);
        if (fbw >= 16 && fbh >= 16) m_s.resize(fbw, fbh);
        mouse();
        keys(dt);
        const std::string grab = script();
        if (now - m_lastPoll > 0.3) {  // the file watcher
            m_lastPoll = now;
            if (m_s.pollInput() && !m_s.error().empty())
                std::fprintf(stderr, "sdftrace view: %s\n", m_s.error().c_str());
        }
        if (m_s.step() || m_s.aov() != m_shown) upload();
        draw(fbw, fbh, grab);
        afterDraw();
    }

  private:
    // Left drag orbits, right or middle drag pans, the wheel zooms.
    void mouse() {
        double x = 0, y = 0;
        glfwGetCursorPos(m_win.handle, &x, &y);
        const float dx = static_cast<float>(x - m_mouseX), dy = static_cast<float>(y - m_mouseY);
        m_mouseX = x;
        m_mouseY = y;
        const double scroll = m_events.scroll;
        m_events.scroll = 0;
        if (ImGui::GetIO().WantCaptureMouse) return;
        auto down = [&](int b) { return glfwGetMouseButton(m_win.handle, b) == GLFW_PRESS; };
        const bool moved = dx != 0 || dy != 0;
        if (moved && down(GLFW_MOUSE_BUTTON_LEFT)) m_s.orbit(dx, dy);
        if (moved && (down(GLFW_MOUSE_BUTTON_RIGHT) || down(GLFW_MOUSE_BUTTON_MIDDLE)))
            m_s.pan(dx, dy);
        if (scroll != 0) m_s.zoom(static_cast<float>(scroll));
    }

    // WASD + QE fly (shift: faster), R resets, P prints the command, F12 screenshots, Tab
    // toggles the panel, Esc closes.
    void keys(double dt) {
        std::vector<int> pressed;
        pressed.swap(m_events.keys);
        if (ImGui::GetIO().WantCaptureKeyboard) return;
        auto held = [&](int k) { return glfwGetKey(m_win.handle, k) == GLFW_PRESS ? 1.0f : 0.0f; };
        const float speed = m_s.flySpeed() * static_cast<float>(dt) *
                            (held(GLFW_KEY_LEFT_SHIFT) != 0 ? 4.0f : 1.0f);
        const float f = held(GLFW_KEY_W) - held(GLFW_KEY_S);
        const float r = held(GLFW_KEY_D) - held(GLFW_KEY_A);
        const float u = held(GLFW_KEY_E) - held(GLFW_KEY_Q);
        if (f != 0 || r != 0 || u != 0) m_s.fly(f * speed, r * speed, u * speed);
        for (int key : pressed) {
            if (key == GLFW_KEY_R) m_s.resetView();
            if (key == GLFW_KEY_P) m_printCommand = true;
            if (key == GLFW_KEY_F12) m_screenshot = true;
            if (key == GLFW_KEY_TAB) m_showPanel = !m_showPanel;
            if (key == GLFW_KEY_ESCAPE) m_quit = true;
        }
    }

    // Runs the script's commands in order until one must wait (`wait` before the picture is
    // refined); returns the path of a `grab`, taken once this pass is drawn.
    std::string script() {
        while (m_next < m_o.script.size() && !m_quit) {
            const ViewCommand& c = m_o.script[m_next];
            if (c.name == "grab") {
                ++m_next;
                imageFormatFromPath(c.args.at(0), "grab");
                checkWritablePath(c.args.at(0), "grab");
                return c.args.at(0);
            }
            std::string out;
            if (!m_s.run(c, m_quit, out)) break;
            if (!out.empty()) std::printf("%s\n", out.c_str());
            std::fflush(stdout);
            ++m_next;
        }
        return "";
    }

    void upload() {
        int w = 0, h = 0;
        const std::vector<uint8_t> rgb = m_s.picture(w, h, m_range);
        glBindTexture(GL_TEXTURE_2D, m_win.texture);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, w, h, 0, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
        m_shown = m_s.aov();
    }

    void draw(int fbw, int fbh, const std::string& grab) {
        ImGui_ImplOpenGL2_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        ImGui::NewFrame();
        ImGui::GetBackgroundDrawList()->AddImage(
            reinterpret_cast<ImTextureID>(static_cast<intptr_t>(m_win.texture)), ImVec2(0, 0),
            ImGui::GetIO().DisplaySize);
        if (m_showPanel) panel(m_s, m_range, m_frames, m_message, m_screenshot, m_printCommand);
        ImGui::Render();
        glViewport(0, 0, fbw, fbh);
        glClearColor(0, 0, 0, 1);
        glClear(GL_COLOR_BUFFER_BIT);
        ImGui_ImplOpenGL2_RenderDrawData(ImGui::GetDrawData());
        if (!grab.empty()) grabWindow(fbw, fbh, grab);
        glfwSwapBuffers(m_win.handle);
    }

    // What the keys and buttons asked for this pass.
    void afterDraw() {
        if (m_printCommand) {
            std::printf("%s\n", m_s.renderCommand().c_str());
            std::fflush(stdout);
        }
        if (m_screenshot) {
            try {
                const std::string path = nextScreenshot(m_o.screenshotDir);
                m_s.screenshot(path);
                m_message = "wrote " + path;
                std::fprintf(stderr, "sdftrace view: %s\n", m_message.c_str());
            } catch (const InputError& e) {
                m_message = e.what();
            }
        }
        m_printCommand = m_screenshot = false;
    }

    ViewerSession& m_s;
    const WindowOptions& m_o;
    Window& m_win;
    Events& m_events;
    bool m_quit = false, m_showPanel, m_screenshot = false, m_printCommand = false;
    float m_range[2] = {0, 0};  // of the AOV shown
    Aov m_shown;
    size_t m_next = 0;  // the next script command
    int m_frames;
    std::string m_message;  // the panel's last note or error
    double m_lastPoll = 0, m_lastTime = 0, m_mouseX = 0, m_mouseY = 0;
};

}  // namespace

int runViewerWindow(ViewerSession& s, const WindowOptions& options) {
    Window win;
    Events events;
    openWindow(win, s, events);
    ViewerLoop loop(s, options, win, events);
    while (loop.running()) loop.pass();
    g_events = nullptr;
    return 0;
}

}  // namespace sdft::cli
