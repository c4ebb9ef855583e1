#include "openvdb_plugin.h"

#include <dlfcn.h>

#include <string>

#include "sdftrace/core/error.h"
#include "sdftrace/core/plugin_dirs.h"

namespace sdft {

namespace {

constexpr const char* kPluginFile = "libsdftrace_openvdb.so";

struct Loaded {
    const OpenVdbPlugin* table = nullptr;
    std::string failure;  // why not, naming every place searched
};

Loaded load() {
    // core/plugin_dirs.h says where it is looked for.
    std::string tried;
    const std::string path = findPlugin(kPluginFile, tried);
    if (!path.empty()) {
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
                         "; `make build` builds it, SDFT_PLUGIN_DIR names its directory)"};
}

}  // namespace

const OpenVdbPlugin& openVdbPlugin(const std::string& purpose) {
    static const Loaded loaded = load();
    if (!loaded.table) throw InputError(purpose + " needs OpenVDB's plugin: " + loaded.failure);
    return *loaded.table;
}

}  // namespace sdft
