#include "openvdb_plugin.h"

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
    std::string failure;
    const auto* table = static_cast<const OpenVdbPlugin*>(
        loadPluginTable(kPluginFile, "sdftrace_openvdb_plugin", failure));
    if (!table) return {nullptr, failure};
    if (table->version != OpenVdbPlugin::kVersion)
        return {nullptr, std::string(kPluginFile) +
                             " is not this build's OpenVDB plugin (rebuild "
                             "sdftrace)"};
    return {table, {}};
}

}  // namespace

const OpenVdbPlugin& openVdbPlugin(const std::string& purpose) {
    static const Loaded loaded = load();
    if (!loaded.table) throw InputError(purpose + " needs OpenVDB's plugin: " + loaded.failure);
    return *loaded.table;
}

}  // namespace sdft
