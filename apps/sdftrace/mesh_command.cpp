// sdftrace mesh field.{sdfg,vdb,sdf,raw} | scene.json | mesh -o out.{ply,obj,stl} [--res N]
//   [--adaptivity A] [--isovalue D]
// The way back from fields to meshes (OpenVDB's volumeToMesh): grids at their own resolution
// (or resampled with --res), scene files sampled at --res, meshes baked exactly at --res first
// (a watertight remesh of a broken scan).
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

#include "commands.h"
#include "sdftrace/bake/extract_surface.h"
#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/exec/progress.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/io/atomic_file.h"
#include "sdftrace/io/grid_file.h"
#include "sdftrace/io/mesh_file.h"
#include "sdftrace/io/mesh_io.h"
#include "sdftrace/io/mesh_write.h"
#include "sdftrace/scene/animated_scene.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/prepare_scene.h"

namespace sdft::cli {

namespace {

constexpr int kDefaultRes = 256;
// An offset surface needs a band that reaches it; wider bands cost memory and time.
constexpr float kMaxOffsetVoxels = 60;

struct MeshArgs {
    std::string input, output;
    std::optional<double> time;  // --time: the instant of an animated scene
    int resolution = 0;          // 0: the grid's own, or kDefaultRes for scenes and meshes
    float adaptivity = 0;
    float isovalue = 0;
    int threads = 0;
    bool quiet = false;
};

SampleOptions sampling(const MeshArgs& a, bool progress) {
    SampleOptions o;
    o.resolution = a.resolution > 0 ? a.resolution : kDefaultRes;
    o.kind = GridKind::Sparse;
    o.blockSize = 8;
    o.threads = a.threads;
    o.progress = progress;
    return o;
}

// The band that holds the offset surface --isovalue asks for and two voxels of samples beyond it.
float bandFor(const Bounds3& region, const MeshArgs& a, int resolution) {
    const float voxel = maxComponent(region.extent()) / resolution;
    const float offsetVoxels = std::fabs(a.isovalue) / voxel;
    if (!(offsetVoxels <= kMaxOffsetVoxels)) {
        char msg[256];
        std::snprintf(msg, sizeof msg,
                      "--isovalue %g: %g voxels from the surface at %d cells; at most %g voxels "
                      "(%g here): lower --res for farther offsets",
                      a.isovalue, offsetVoxels, resolution, kMaxOffsetVoxels,
                      kMaxOffsetVoxels * voxel);
        throw InputError(msg);
    }
    return std::max(3.0f, offsetVoxels + 2.0f);
}

// Samples a field's tape over `region` at --res (the field's own distances, no culling).
Grid sampleField(const NodePtr& root, const Bounds3* regionOrNull, const MeshArgs& a,
                 bool progress) {
    Tape tape = compileTape(root, {.boundsCulling = false});
    const Bounds3 region = regionOrNull ? *regionOrNull : tape.bounds();
    if (!region.finite() || region.empty())
        throw InputError(a.input +
                         ": the scene is unbounded (a plane or a complement?); mesh a bounded "
                         "part of it, e.g. intersected with a box");
    SampleOptions o = sampling(a, progress);
    o.bandVoxels = bandFor(region, a, o.resolution);
    return sampleGrid(tape, region, o);
}

Grid fieldOf(const MeshArgs& a, bool progress, std::string& how) {
    if (a.time && (isGridFile(a.input) || isMeshFile(a.input)))
        throw InputError("--time: " + a.input +
                         " is not a scene file; --time picks the instant of a scene file with "
                         "keyframes");
    if (isGridFile(a.input)) {
        Grid g = loadGridFile(a.input);
        if (a.resolution <= 0) {
            how = "its own " + std::to_string(g.shape().cells[0]) + "x" +
                  std::to_string(g.shape().cells[1]) + "x" + std::to_string(g.shape().cells[2]) +
                  " cells";
            return g;
        }
        how = "resampled at " + std::to_string(a.resolution) + " cells";
        const Bounds3 region = g.surfaceBounds();
        if (region.empty())
            throw InputError(a.input + ": the grid contains no surface (no sign change)");
        return sampleField(node::grid(std::make_shared<const Grid>(std::move(g))), &region, a,
                           progress);
    }
    if (isMeshFile(a.input)) {
        MeshReport report;
        TriangleMesh mesh = loadMesh(a.input, &report);
        if (!a.quiet)
            std::fprintf(stderr, "sdftrace mesh: %s: %s\n", a.input.c_str(),
                         report.summary().c_str());
        MeshBakeOptions o;
        o.sampling = sampling(a, progress);
        o.sampling.bandVoxels = bandFor(mesh.bounds(), a, o.sampling.resolution);
        o.progress = progress;
        how = "baked exactly at " + std::to_string(o.sampling.resolution) + " cells";
        return bakeMesh(mesh, o).grid;
    }
    AssetCache cache;
    Scene scene = a.time ? AnimatedScene::fromFile(a.input).at(
                               *a.time, cache, PrepareOptions{.progress = progress, .bakeMesh = {}})
                         : describeSceneFile(a.input);
    if (!a.time) prepareScene(scene, cache, PrepareOptions{.progress = progress, .bakeMesh = {}});
    how = "sampled at " + std::to_string(a.resolution > 0 ? a.resolution : kDefaultRes) + " cells";
    return sampleField(scene.root, nullptr, a, progress);
}

int runMesh(const MeshArgs& a) {
    if (!isMeshOutputFile(a.output))
        throw InputError("--output " + a.output +
                         ": accepted extensions: .ply (binary), .obj, .stl (binary)");
    checkWritablePath(a.output, "--output");
    const bool progress = !a.quiet && stderrIsTerminal();
    std::unique_ptr<tbb::global_control> threads;
    if (a.threads > 0)
        threads = std::make_unique<tbb::global_control>(
            tbb::global_control::max_allowed_parallelism, a.threads);
    auto t0 = std::chrono::steady_clock::now();
    std::string how;
    Grid grid = fieldOf(a, progress, how);
    const double fieldSeconds = since(t0);
    if (!a.quiet) std::fprintf(stderr, "sdftrace mesh: contouring (volumeToMesh)...\n");
    ExtractOptions o;
    o.adaptivity = a.adaptivity;
    o.isovalue = a.isovalue;
    ExtractStats st;
    TriangleMesh mesh = extractSurface(grid, o, a.input, &st);
    t0 = std::chrono::steady_clock::now();
    saveMesh(mesh, a.output);
    std::fprintf(stderr,
                 "sdftrace mesh: %s -> %s: %zu vertices, %zu triangles (%zu quads split), field "
                 "(%s) %.3f s, to OpenVDB %.3f s, contour %.3f s, write %.3f s\n",
                 a.input.c_str(), a.output.c_str(), mesh.positions.size(), mesh.triangles.size(),
                 st.quads, how.c_str(), fieldSeconds, st.convertSeconds, st.contourSeconds,
                 since(t0));
    return 0;
}

}  // namespace

void addMeshCommand(CLI::App& app, Action& action) {
    auto args = std::make_shared<MeshArgs>();
    CLI::App* cmd = app.add_subcommand(
        "mesh",
        "Extract a field's surface as a triangle mesh (OpenVDB's volumeToMesh, adaptive dual "
        "contouring) from a grid file, a scene file or a mesh (a watertight remesh)");
    cmd->add_option("input", args->input,
                    "Grid file (.sdfg, .vdb, .sdf, .raw), scene file (JSON) or mesh (.obj, .ply, "
                    ".stl, .off, .gltf, .glb)")
        ->required();
    cmd->add_option("-o,--output", args->output,
                    "Output mesh: .ply (binary little-endian), .obj or .stl (binary)")
        ->required();
    cmd->add_option("--res", args->resolution,
                    "Cells along the longest axis: scene files and meshes are sampled at it "
                    "(default 256); grid files are resampled to it (default: their own cells)")
        ->check(CLI::Range(8, 4096));
    cmd->add_option("--adaptivity", args->adaptivity,
                    "0 keeps one polygon per surface voxel; up to 1 merges flat regions into "
                    "fewer, larger polygons")
        ->check(CLI::Range(0.0, 1.0))
        ->capture_default_str();
    cmd->add_option("--isovalue", args->isovalue,
                    "Distance of the extracted surface from the field's zero level, in world "
                    "units (> 0: an offset surface outside)")
        ->capture_default_str();
    cmd->add_option("--threads", args->threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, 1024));
    cmd->add_option("--time", args->time,
                    "Extract a scene file's surface at this time in seconds (its keyframed "
                    "values; default: the animation's start)")
        ->check(CLI::Range(-1e9, 1e9));
    cmd->add_flag("-q,--quiet", args->quiet, "No progress on stderr (the summary line stays)");
    cmd->callback([&action, args] { action = [args] { return runMesh(*args); }; });
}

}  // namespace sdft::cli
