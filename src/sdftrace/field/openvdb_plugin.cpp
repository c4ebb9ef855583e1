#include "openvdb_plugin.h"

#include <dlfcn.h>
#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <mutex>

#include "sdftrace/core/error.h"

namespace sdft {

namespace {

constexpr const char* kPluginFile = "libsdftrace_openvdb.so";

std::string executableDir() {
    char buf[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", buf, sizeof buf - 1);
    if (n <= 0) return {};
    std::string path(buf, static_cast<size_t>(n));
    const size_t slash = path.rfind('/');
    return slash == std::string::npos ? std::string{} : path.substr(0, slash);
}

struct Loaded {
    const OpenVdbPlugin* table = nullptr;
    std::string failure;  // why not, naming every place searched
};

Loaded load() {
    // $SDFT_PLUGIN_DIR alone when set; otherwise beside the executable, then the build tree.
    std::vector<std::string> dirs;
    if (const char* env = std::getenv("SDFT_PLUGIN_DIR"); env && *env) {
        dirs.push_back(env);
    } else {
        if (std::string exe = executableDir(); !exe.empty()) dirs.push_back(exe);
#ifdef SDFT_PLUGIN_BUILD_DIR
        dirs.push_back(SDFT_PLUGIN_BUILD_DIR);
#endif
    }
    std::string tried;
    for (const std::string& dir : dirs) {
        const std::string path = dir + "/" + kPluginFile;
        if (access(path.c_str(), R_OK) != 0) {
            tried += (tried.empty() ? "" : ", ") + path;
            continue;
        }
        void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) return {nullptr, "cannot load " + path + " (" + dlerror() + ")"};
        auto entry =
            reinterpret_cast<const OpenVdbPlugin* (*)()>(dlsym(handle, "sdftrace_openvdb_plugin"));
        const OpenVdbPlugin* table = entry ? entry() : nullptr;
        if (!table || table->version != OpenVdbPlugin::kVersion)
            return {nullptr, path + " is not this build's OpenVDB plugin (rebuild sdftrace)"};
        return {table, {}};
    }
    return {nullptr, kPluginFile + std::string(" not found (looked for ") + tried +
                         "; set SDFT_PLUGIN_DIR to its directory)"};
}

}  // namespace

const OpenVdbPlugin& openVdbPlugin(const std::string& purpose) {
    static const Loaded loaded = load();
    if (!loaded.table) throw InputError(purpose + " needs OpenVDB's plugin: " + loaded.failure);
    return *loaded.table;
}

}  // namespace sdft
