#include "plugin_dirs.h"

#include <dlfcn.h>
#include <unistd.h>

#include <climits>
#include <cstdlib>

namespace sdft {

namespace {

std::string directoryOf(const std::string& path) {
    const size_t slash = path.rfind('/');
    return slash == std::string::npos ? std::string{} : path.substr(0, slash);
}

// The directory of the binary this code is linked into: the executable for the CLI and programs
// linking the library, the extension module for Python.
std::string binaryDir() {
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&directoryOf), &info) && info.dli_fname &&
        info.dli_fname[0] == '/')
        return directoryOf(info.dli_fname);
    char buf[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", buf, sizeof buf - 1);
    if (n <= 0) return {};
    return directoryOf(std::string(buf, static_cast<size_t>(n)));
}

}  // namespace

std::vector<std::string> pluginSearchDirs() {
    std::vector<std::string> dirs;
    if (const char* env = std::getenv("SDFT_PLUGIN_DIR"); env && *env) {
        dirs.push_back(env);
        return dirs;
    }
    if (std::string dir = binaryDir(); !dir.empty()) {
        dirs.push_back(dir);
#ifdef SDFT_PLUGIN_LIBDIR
        dirs.push_back(dir + "/../" SDFT_PLUGIN_LIBDIR "/sdftrace");
#endif
    }
#ifdef SDFT_PLUGIN_INSTALL_DIR
    dirs.push_back(SDFT_PLUGIN_INSTALL_DIR);
#endif
#ifdef SDFT_PLUGIN_BUILD_DIR
    dirs.push_back(SDFT_PLUGIN_BUILD_DIR);
#endif
    return dirs;
}

std::string findPlugin(const std::string& file, std::string& tried) {
    tried.clear();
    for (const std::string& dir : pluginSearchDirs()) {
        const std::string path = dir + "/" + file;
        if (access(path.c_str(), R_OK) == 0) return path;
        tried += (tried.empty() ? "" : ", ") + path;
    }
    return {};
}

const void* loadPluginTable(const std::string& file, const char* symbol, std::string& failure) {
    std::string tried;
    const std::string path = findPlugin(file, tried);
    if (path.empty()) {
        failure = file + " not found (looked for " + tried +
                  "; `make build` builds it, SDFT_PLUGIN_DIR names its directory)";
        return nullptr;
    }
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
        failure = "cannot load " + path + " (" + dlerror() + ")";
        return nullptr;
    }
    auto entry = reinterpret_cast<const void* (*)()>(dlsym(handle, symbol));
    const void* table = entry ? entry() : nullptr;
    if (!table) failure = path + " has no " + symbol + " (rebuild sdftrace)";
    return table;
}

}  // namespace sdft
