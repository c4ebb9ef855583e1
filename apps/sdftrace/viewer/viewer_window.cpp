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
           bool& screenshot, bool& printCommand, bool& refresh) {
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
    if (ImGui::Combo("AOV", &aov, kAovs, IM_ARRAYSIZE(kAovs))) {
        s.setAov(static_cast<Aov>(aov));
        refresh = true;
    }
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

}  // namespace

int runViewerWindow(ViewerSession& s, const WindowOptions& options) {
    glfwSetErrorCallback([](int, const char* text) { g_glfwError = text ? text : ""; });
    Window win;
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
    Events events;
    g_events = &events;
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

    bool quit = false, showPanel = options.panel, picture = false;
    float range[2] = {0, 0};  // of the AOV shown
    Aov shown = s.aov();
    size_t next = 0;
    int frames = s.frames();
    std::string message;
    double lastPoll = glfwGetTime(), lastTime = glfwGetTime();
    double mouseX = 0, mouseY = 0;
    glfwGetCursorPos(win.handle, &mouseX, &mouseY);
    while (!quit && !glfwWindowShouldClose(win.handle)) {
        const bool idle = s.refined() && next >= options.script.size();
        if (idle)
            glfwWaitEventsTimeout(0.25);  // still: wake for input or the file watcher
        else
            glfwPollEvents();
        const double now = glfwGetTime(), dt = std::min(0.1, now - lastTime);
        lastTime = now;
        ImGuiIO& io = ImGui::GetIO();
        int fbw = 0, fbh = 0;
        glfwGetFramebufferSize(win.handle, &fbw, &fbh);
        if (fbw >= 16 && fbh >= 16) s.resize(fbw, fbh);

        // Mouse: left drag orbits, right or middle drag pans, the wheel zooms.
        double x = 0, y = 0;
        glfwGetCursorPos(win.handle, &x, &y);
        const float dx = static_cast<float>(x - mouseX), dy = static_cast<float>(y - mouseY);
        mouseX = x;
        mouseY = y;
        if (!io.WantCaptureMouse) {
            if (glfwGetMouseButton(win.handle, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS &&
                (dx != 0 || dy != 0))
                s.orbit(dx, dy);
            if ((glfwGetMouseButton(win.handle, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS ||
                 glfwGetMouseButton(win.handle, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS) &&
                (dx != 0 || dy != 0))
                s.pan(dx, dy);
            if (events.scroll != 0) s.zoom(static_cast<float>(events.scroll));
        }
        events.scroll = 0;
        // Keys: WASD + QE fly (shift: faster), R resets, P prints the command, F12 screenshots,
        // Tab toggles the panel, Esc closes.
        bool screenshot = false, printCommand = false;
        if (!io.WantCaptureKeyboard) {
            const float speed = s.flySpeed() * static_cast<float>(dt) *
                                (glfwGetKey(win.handle, GLFW_KEY_LEFT_SHIFT) ? 4.0f : 1.0f);
            auto held = [&](int k) {
                return glfwGetKey(win.handle, k) == GLFW_PRESS ? 1.0f : 0.0f;
            };
            const float f = held(GLFW_KEY_W) - held(GLFW_KEY_S);
            const float r = held(GLFW_KEY_D) - held(GLFW_KEY_A);
            const float u = held(GLFW_KEY_E) - held(GLFW_KEY_Q);
            if (f != 0 || r != 0 || u != 0) s.fly(f * speed, r * speed, u * speed);
            for (int key : events.keys) {
                if (key == GLFW_KEY_R) s.resetView();
                if (key == GLFW_KEY_P) printCommand = true;
                if (key == GLFW_KEY_F12) screenshot = true;
                if (key == GLFW_KEY_TAB) showPanel = !showPanel;
                if (key == GLFW_KEY_ESCAPE) quit = true;
            }
        }
        events.keys.clear();

        // The script: commands run in order; `wait` holds until the picture is refined.
        std::string grab;
        while (next < options.script.size()) {
            if (options.script[next].name == "grab") {  // after this frame is drawn
                grab = options.script[next++].args.at(0);
                imageFormatFromPath(grab, "grab");
                checkWritablePath(grab, "grab");
                break;
            }
            std::string out;
            if (!s.run(options.script[next], quit, out)) break;
            if (!out.empty()) std::printf("%s\n", out.c_str());
            std::fflush(stdout);
            ++next;
            if (quit) break;
        }
        if (now - lastPoll > 0.3) {  // the file watcher
            lastPoll = now;
            if (s.pollInput() && !s.error().empty())
                std::fprintf(stderr, "sdftrace view: %s\n", s.error().c_str());
        }
        if (s.step() || s.aov() != shown) picture = true;
        shown = s.aov();

        if (picture) {
            int w = 0, h = 0;
            const std::vector<uint8_t> rgb = s.picture(w, h, range);
            glBindTexture(GL_TEXTURE_2D, win.texture);
            glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
            glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, w, h, 0, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
            picture = false;
        }
        ImGui_ImplOpenGL2_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        ImGui::NewFrame();
        ImGui::GetBackgroundDrawList()->AddImage(
            reinterpret_cast<ImTextureID>(static_cast<intptr_t>(win.texture)), ImVec2(0, 0),
            io.DisplaySize);
        if (showPanel) panel(s, range, frames, message, screenshot, printCommand, picture);
        ImGui::Render();
        glViewport(0, 0, fbw, fbh);
        glClearColor(0, 0, 0, 1);
        glClear(GL_COLOR_BUFFER_BIT);
        ImGui_ImplOpenGL2_RenderDrawData(ImGui::GetDrawData());
        if (!grab.empty()) grabWindow(fbw, fbh, grab);
        glfwSwapBuffers(win.handle);
        if (printCommand) {
            std::printf("%s\n", s.renderCommand().c_str());
            std::fflush(stdout);
        }
        if (screenshot) {
            try {
                const std::string path = nextScreenshot(options.screenshotDir);
                s.screenshot(path);
                message = "wrote " + path;
                std::fprintf(stderr, "sdftrace view: %s\n", message.c_str());
            } catch (const InputError& e) {
                message = e.what();
            }
        }
    }
    g_events = nullptr;
    return 0;
}

}  // namespace sdft::cli
