// Where sdftrace looks for its plugins (the OpenVDB tools, video encoding, the GPU renderer's
// kernels): modules loaded on first use, so that programs that never need them do not pay for
// loading or building them (docs/decisions/0008, 0015).
#pragma once

#include <string>
#include <vector>

namespace sdft {

// $SDFT_PLUGIN_DIR alone when it is set; otherwise the directory of the binary this code is
// linked into (the executable, or the Python extension module), <that>/../lib/sdftrace (an
// installed tree's bin/), where this build installs, then this build's tree.
std::vector<std::string> pluginSearchDirs();

// The first readable `<dir>/<file>` of pluginSearchDirs(); empty when none. `tried` lists every
// path looked at (for the error line).
std::string findPlugin(const std::string& file, std::string& tried);

// Loads plugin `file` (findPlugin) and returns what its entry point `symbol` (a function of no
// arguments) returns: its table. Null with `failure` set, naming the places searched or what
// dlopen said, when it is missing or cannot be loaded.
const void* loadPluginTable(const std::string& file, const char* symbol, std::string& failure);

}  // namespace sdft
