// The viewer's window (GLFW + OpenGL 2 + Dear ImGui), built where those libraries are found: it
// forwards the mouse, the keys and the script to a ViewerSession, shows its pictures and draws the
// panel (docs/viewer.md).
#pragma once
#include <string>
#include <vector>

#include "sdftrace/view/view_script.h"
#include "sdftrace/view/viewer_session.h"

namespace sdft::cli {

struct WindowOptions {
    std::vector<ViewCommand> script;
    std::string screenshotDir = ".";
    bool panel = true;
};

// Runs until the window closes or the script quits; the exit status. Throws InputError when no
// window can be opened, and for a script command that fails.
int runViewerWindow(ViewerSession& session, const WindowOptions& options);

}  // namespace sdft::cli
