// sdftrace info field.sdfg [--full]
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "sdftrace/bake/texture_coords.h"
#include "sdftrace/io/grid_file.h"
#include "sdftrace/io/sdfg_io.h"

namespace sdft::cli {

namespace {
constexpr double kMiB = 1048576.0;

// The lines every grid shares: layout, cells, voxel size, bounds.
void printShape(const std::string& path, GridKind kind, const GridShape& s) {
    const Bounds3 b = s.bounds();
    std::printf("file:        %s\n", path.c_str());
    std::printf("kind:        %s\n", kind == GridKind::Dense ? "dense" : "sparse block grid");
    std::printf("cells:       %d x %d x %d (%d x %d x %d samples)\n", s.cells[0], s.cells[1],
                s.cells[2], s.vertices(0), s.vertices(1), s.vertices(2));
    std::printf("voxel size:  %.6g\n", s.voxelSize);
    std::printf("bounds:      [%.6g, %.6g, %.6g] - [%.6g, %.6g, %.6g]\n", b.lo.x, b.lo.y, b.lo.z,
                b.hi.x, b.hi.y, b.hi.z);
}

void printBlocks(const GridShape& s, int blockSize, float background, const BlockCounts& n,
                 double memoryBytes) {
    std::printf("block size:  %d^3 cells\n", blockSize);
    std::printf("blocks:      %zu surface, %zu inside, %zu outside (%zu total)\n", n.surface,
                n.inside, n.outside, n.surface + n.inside + n.outside);
    std::printf("background:  %.6g (distance bound outside the band)\n", background);
    std::printf("dense size:  %.3f MiB (sparse saves %.1f%%)\n", s.vertexCount() * 4 / kMiB,
                100.0 * (1.0 - memoryBytes / (s.vertexCount() * 4.0)));
}

// A .sdfg file from its header and tables: no sample is read, so it takes milliseconds at any
// size.
int runSummary(const std::string& path) {
    const SdfgSummary r = readSdfgSummary(path);
    printShape(path, r.kind, r.shape);
    std::printf("file size:   %.3f MiB (.sdfg version %u%s)\n", r.fileBytes / kMiB, r.version,
                r.version >= 3 ? ", zstd-compressed" : "");
    std::printf("memory:      about %.3f MiB once loaded\n", r.memoryBytes / kMiB);
    std::printf("lipschitz:   not computed (info --full reads every sample for it)\n");
    if (r.texcoords != TexcoordKind::None)
        std::printf("texcoords:   projected from a %s helper, 3 floats per sample (%.3f MiB)\n",
                    texcoordKindName(r.texcoords), 3 * r.sampleBytes / kMiB);
    else
        std::printf("texcoords:   none\n");
    if (r.kind == GridKind::Sparse)
        printBlocks(r.shape, r.blockSize, r.background, r.blocks,
                    static_cast<double>(r.memoryBytes));
    return 0;
}

// Any grid file, loaded whole: its memory and Lipschitz bound measured.
int runFull(const std::string& path) {
    Grid g = loadGridFile(path);
    printShape(path, g.kind(), g.shape());
    std::printf("memory:      %.3f MiB\n", g.memoryBytes() / kMiB);
    std::printf("lipschitz:   %.4f (of the trilinear reconstruction)\n", g.lipschitz());
    if (g.texcoordKind() != TexcoordKind::None)
        std::printf("texcoords:   projected from a %s helper, 3 floats per sample (%.3f MiB)\n",
                    texcoordKindName(g.texcoordKind()), g.texcoords().size() * 4 / kMiB);
    else
        std::printf("texcoords:   none\n");
    if (g.kind() == GridKind::Sparse) {
        BlockCounts n;
        g.blockCounts(n.inside, n.outside, n.surface);
        printBlocks(g.shape(), g.blockSize(), g.background(), n,
                    static_cast<double>(g.memoryBytes()));
    }
    return 0;
}
}  // namespace

void addInfoCommand(CLI::App& app, Action& action) {
    auto path = std::make_shared<std::string>();
    auto full = std::make_shared<bool>(false);
    CLI::App* cmd = app.add_subcommand(
        "info",
        "Describe a grid file (.sdfg, .vdb, .sdf or .raw): size, voxel size, bounds, layout, "
        "memory. A .sdfg is described from its header and block table (milliseconds at any "
        "size); --full, and the other formats, load it");
    cmd->add_option("file", *path, "Grid file (.sdfg, .vdb, .sdf, .raw)")->required();
    cmd->add_flag("--full", *full,
                  "Load the whole grid: its memory measured, the Lipschitz bound of its "
                  "reconstruction computed, every sample's checksum checked");
    cmd->callback([&action, path, full] {
        action = [path, full] {
            const bool summary = !*full && std::filesystem::path(*path).extension() == ".sdfg";
            return summary ? runSummary(*path) : runFull(*path);
        };
    });
}

}  // namespace sdft::cli
