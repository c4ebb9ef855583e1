// sdftrace convert in.{sdfg,vdb,sdf,raw} out.{sdfg,vdb,sdf,raw}
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "sdftrace/core/error.h"
#include "sdftrace/io/atomic_file.h"
#include "sdftrace/io/grid_file.h"
#include "sdftrace/io/sdfg_io.h"

namespace sdft::cli {

namespace {
struct ConvertArgs {
    std::string input, output;
    bool uncompressed = false;
};

int runConvert(const ConvertArgs& a) {
    if (!isGridFile(a.output))
        throw InputError("output " + a.output +
                         ": accepted extensions: .sdfg, .vdb, .sdf (SDFGen), .raw (float32 with a "
                         ".raw.json sidecar)");
    const bool sdfg = std::filesystem::path(a.output).extension() == ".sdfg";
    if (a.uncompressed && !sdfg)
        throw InputError("--uncompressed: applies to .sdfg outputs only, not " + a.output);
    checkWritablePath(a.output, "output");
    Grid g = loadGridFile(a.input);
    if (g.texcoordKind() != TexcoordKind::None &&
        std::filesystem::path(a.output).extension() != ".sdfg")
        std::fprintf(stderr,
                     "sdftrace convert: warning: %s has texture coordinates; %s holds distances "
                     "only, so they are not written (keep the .sdfg to texture it)\n",
                     a.input.c_str(), a.output.c_str());
    if (sdfg)
        saveSdfg(g, a.output, {.compress = !a.uncompressed});
    else
        saveGridFile(g, a.output);
    const GridShape& s = g.shape();
    std::fprintf(stderr, "sdftrace convert: %s -> %s, %dx%dx%d cells, voxel %.4g\n",
                 a.input.c_str(), a.output.c_str(), s.cells[0], s.cells[1], s.cells[2],
                 s.voxelSize);
    return 0;
}
}  // namespace

void addConvertCommand(CLI::App& app, Action& action) {
    auto args = std::make_shared<ConvertArgs>();
    CLI::App* cmd = app.add_subcommand(
        "convert",
        "Convert grids between .sdfg, OpenVDB float level sets (.vdb), SDFGen's text format (.sdf) "
        "and raw float32 samples with a JSON sidecar (.raw + .raw.json), any way");
    cmd->add_option("input", args->input, "Input grid (.sdfg, .vdb, .sdf or .raw)")->required();
    cmd->add_option("output", args->output, "Output grid (.sdfg, .vdb, .sdf or .raw)")->required();
    cmd->add_flag(
        "--uncompressed", args->uncompressed,
        ".sdfg: write version 1 (2 with texture coordinates), the raw buffers, instead of "
        "the compressed version 5 (4 for dense grids)");
    cmd->callback([&action, args] { action = [args] { return runConvert(*args); }; });
}

}  // namespace sdft::cli
