// sdftrace info field.sdfg
#include <cstdio>

#include "commands.h"
#include "sdftrace/bake/texture_coords.h"
#include "sdftrace/io/grid_file.h"

namespace sdft::cli {

namespace {
int runInfo(const std::string& path) {
    Grid g = loadGridFile(path);
    const GridShape& s = g.shape();
    Bounds3 b = s.bounds();
    std::printf("file:        %s\n", path.c_str());
    std::printf("kind:        %s\n", g.kind() == GridKind::Dense ? "dense" : "sparse block grid");
    std::printf("cells:       %d x %d x %d (%d x %d x %d samples)\n", s.cells[0], s.cells[1],
                s.cells[2], s.vertices(0), s.vertices(1), s.vertices(2));
    std::printf("voxel size:  %.6g\n", s.voxelSize);
    std::printf("bounds:      [%.6g, %.6g, %.6g] - [%.6g, %.6g, %.6g]\n", b.lo.x, b.lo.y, b.lo.z,
                b.hi.x, b.hi.y, b.hi.z);
    std::printf("memory:      %.3f MiB\n", g.memoryBytes() / 1048576.0);
    std::printf("lipschitz:   %.4f (of the trilinear reconstruction)\n", g.lipschitz());
    if (g.texcoordKind() != TexcoordKind::None)
        std::printf("texcoords:   projected from a %s helper, 3 floats per sample (%.3f MiB)\n",
                    texcoordKindName(g.texcoordKind()), g.texcoords().size() * 4 / 1048576.0);
    else
        std::printf("texcoords:   none\n");
    if (g.kind() == GridKind::Sparse) {
        size_t in, out, surf;
        g.blockCounts(in, out, surf);
        std::printf("block size:  %d^3 cells\n", g.blockSize());
        std::printf("blocks:      %zu surface, %zu inside, %zu outside (%zu total)\n", surf, in,
                    out, surf + in + out);
        std::printf("background:  %.6g (distance bound outside the band)\n", g.background());
        std::printf("dense size:  %.3f MiB (sparse saves %.1f%%)\n",
                    s.vertexCount() * 4 / 1048576.0,
                    100.0 * (1.0 - g.memoryBytes() / (s.vertexCount() * 4.0)));
    }
    return 0;
}
}  // namespace

void addInfoCommand(CLI::App& app, Action& action) {
    auto path = std::make_shared<std::string>();
    CLI::App* cmd = app.add_subcommand("info",
                                       "Describe a grid file (.sdfg, .vdb, .sdf or .raw): size, "
                                       "voxel size, bounds, layout, memory");
    cmd->add_option("file", *path, "Grid file (.sdfg)")->required();
    cmd->callback([&action, path] { action = [path] { return runInfo(*path); }; });
}

}  // namespace sdft::cli
