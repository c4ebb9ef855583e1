#include "sdftrace/io/grid_file.h"

#include <filesystem>

#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/io/raw_grid_io.h"
#include "sdftrace/io/sdfg_io.h"
#include "sdftrace/io/sdfgen_io.h"
#include "sdftrace/io/vdb_io.h"

namespace sdft {

namespace {
std::string extensionOf(const std::string& path) {
    return std::filesystem::path(path).extension().string();
}
}  // namespace

bool isGridFile(const std::string& path) {
    std::string e = extensionOf(path);
    return e == ".sdfg" || e == ".vdb" || e == ".sdf" || e == ".raw";
}

Grid loadGridFile(const std::string& path) {
    std::string e = extensionOf(path);
    if (e == ".sdfg") return loadSdfg(path);
    if (e == ".sdf") return readWithinBudget(path, [&] { return loadSdfgen(path); });
    if (e == ".raw") return readWithinBudget(path, [&] { return loadRawGrid(path); });
    if (e == ".vdb") {
        if (!std::filesystem::exists(path))
            throw InputError(path + ": cannot open grid file (does it exist?)");
        return loadVdb(path);
    }
    throw InputError(
        path + ": unknown grid file extension '" + e +
        "'; accepted: .sdfg, .vdb, .sdf (SDFGen), .raw (float32 with a .raw.json sidecar)");
}

void saveGridFile(const Grid& grid, const std::string& path) {
    std::string e = extensionOf(path);
    if (e == ".sdfg") return saveSdfg(grid, path);
    if (e == ".sdf") return saveSdfgen(grid, path);
    if (e == ".raw") return saveRawGrid(grid, path);
    if (e == ".vdb") return saveVdb(grid, path);
    throw InputError(
        path + ": unknown grid file extension '" + e +
        "'; accepted: .sdfg, .vdb, .sdf (SDFGen), .raw (float32 with a .raw.json sidecar)");
}

}  // namespace sdft
