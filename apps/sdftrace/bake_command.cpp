// sdftrace bake scene.json --res N -o field.sdfg [--dense | --sparse] [--block 4|8] [--band W]
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <numeric>

#include "commands.h"
#include "sdftrace/bake/exact_bake.h"
#include "sdftrace/bake/jump_flood.h"
#include "sdftrace/core/error.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/io/atomic_file.h"
#include "sdftrace/io/grid_file.h"
#include "sdftrace/io/mesh_file.h"
#include "sdftrace/io/mesh_io.h"
#include "sdftrace/scene/parse_scene.h"

namespace sdft::cli {

namespace {

struct BakeArgs {
    std::string scene;
    std::string output;
    int resolution = 128;
    bool dense = false, sparse = false;
    int blockSize = 4;
    float band = 3;
    std::string bounds;
    std::string method = "exact";
    std::string sign = "winding";
    std::string jfaVariant = "plain";
    bool verify = false;
    int threads = 0;
};

Bounds3 parseBoundsArg(const std::string& text) {
    std::vector<float> v;
    size_t start = 0;
    while (start <= text.size()) {
        size_t comma = text.find(',', start);
        std::string part =
            text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        try {
            size_t used = 0;
            v.push_back(std::stof(part, &used));
            if (used != part.size() || !std::isfinite(v.back())) throw std::invalid_argument(part);
        } catch (const std::exception&) {
            throw InputError("--bounds: expected six finite numbers x0,y0,z0,x1,y1,z1, got '" +
                             text + "'");
        }
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    if (v.size() != 6 || v[0] >= v[3] || v[1] >= v[4] || v[2] >= v[5]) {
        throw InputError(
            "--bounds: expected six numbers x0,y0,z0,x1,y1,z1 with x0 < x1, y0 < y1, z0 < z1, got "
            "'" +
            text + "'");
    }
    return {{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
}

SampleOptions sampleOptions(const BakeArgs& a) {
    SampleOptions o;
    o.resolution = a.resolution;
    o.kind = a.dense ? GridKind::Dense : GridKind::Sparse;
    o.blockSize = a.blockSize;
    o.bandVoxels = a.band;
    o.threads = a.threads;
    return o;
}

// Mean, 99th percentile and maximum of |baked| - |exact| in voxels over `mask`, and wrong signs.
void printVerify(const char* what, const std::vector<float>& baked, const std::vector<float>& exact,
                 float voxel, float band) {
    std::vector<double> all, near;
    size_t wrong = 0;
    for (size_t i = 0; i < baked.size(); ++i) {
        double e = std::fabs(std::fabs(baked[i]) - std::fabs(exact[i])) / voxel;
        all.push_back(e);
        if (std::fabs(exact[i]) < band) near.push_back(e);
        wrong += (baked[i] < 0) != (exact[i] < 0);
    }
    auto report = [&](const char* where, std::vector<double>& v) {
        if (v.empty()) return;
        std::sort(v.begin(), v.end());
        double mean = std::accumulate(v.begin(), v.end(), 0.0) / v.size();
        std::fprintf(stderr, "sdftrace bake: verify %s, %s: mean %.4f, p99 %.4f, max %.4f voxels\n",
                     what, where, mean, v[v.size() * 99 / 100], v.back());
    };
    report("all samples", all);
    report("narrow band", near);
    std::fprintf(stderr, "sdftrace bake: verify %s: %.4f%% of samples with the wrong sign\n", what,
                 100.0 * wrong / baked.size());
}

// A mesh file: exact (Embree closest points) or jump flooding (RTSDF §2.2), signed by the
// winding number or ray parity; --verify compares with the exact bake.
int bakeMesh(const BakeArgs& a) {
    if (a.method != "exact" && a.method != "jfa" && a.method != "danielsson") {
        throw InputError("--method " + a.method +
                         ": not implemented yet; accepted: exact, jfa, danielsson");
    }
    auto t0 = std::chrono::steady_clock::now();
    MeshReport report;
    TriangleMesh mesh = loadMesh(a.scene, &report);
    std::fprintf(stderr, "sdftrace bake: %s: %s\n", a.scene.c_str(), report.summary().c_str());
    auto t1 = std::chrono::steady_clock::now();
    SampleOptions o = sampleOptions(a);
    GridShape shape = gridShapeFor(mesh.bounds(), o);
    SignMethod sign = a.sign == "parity" ? SignMethod::RayParity : SignMethod::WindingNumber;
    std::vector<float> samples;
    std::unique_ptr<MeshBvh> bvh;
    if (a.method == "exact" || a.verify) bvh = std::make_unique<MeshBvh>(mesh);
    if (a.method == "exact") {
        samples = bakeExactSamples(*bvh, shape, sign, a.threads);
    } else if (a.method == "danielsson") {
        samples = bakeDanielssonSamples(mesh, shape, a.threads);
    } else {
        JfaVariant v = a.jfaVariant == "1+jfa"   ? JfaVariant::OnePlusJfa
                       : a.jfaVariant == "jfa+2" ? JfaVariant::JfaPlusTwo
                                                 : JfaVariant::Plain;
        JfaStats st;
        samples = bakeJumpFloodSamples(mesh, shape, v, a.threads, &st);
        std::fprintf(stderr, "sdftrace bake: jump flooding, %d passes, %.3f s\n", st.passes,
                     st.seconds);
    }
    auto t2 = std::chrono::steady_clock::now();
    if (a.verify) {
        std::vector<float> exact =
            bakeExactSamples(*bvh, shape, SignMethod::WindingNumber, a.threads);
        printVerify(a.method.c_str(), samples, exact, shape.voxelSize, a.band * shape.voxelSize);
    }
    Grid grid = o.kind == GridKind::Dense
                    ? Grid::dense(shape, std::move(samples))
                    : Grid::sparseFromDense(shape, samples, o.blockSize, o.bandVoxels);
    saveGridFile(grid, a.output);
    std::fprintf(
        stderr,
        "sdftrace bake: %dx%dx%d cells (voxel %.4g), %s, %.2f MiB; load %.3f s, %s bake %.3f s\n",
        shape.cells[0], shape.cells[1], shape.cells[2], shape.voxelSize,
        grid.kind() == GridKind::Dense ? "dense" : "sparse", grid.memoryBytes() / 1048576.0,
        std::chrono::duration<double>(t1 - t0).count(), a.method.c_str(),
        std::chrono::duration<double>(t2 - t1).count());
    return 0;
}

int runBake(const BakeArgs& a) {
    if (!isGridFile(a.output))
        throw InputError("--output " + a.output + ": accepted extensions: .sdfg, .vdb");
    checkWritablePath(a.output, "--output");
    if (isMeshFile(a.scene)) return bakeMesh(a);
    Scene scene = parseSceneFile(a.scene);
    // The field's definition (no culling): sampled values should be the field, not a looser bound.
    Tape tape = compileTape(scene.root, {.boundsCulling = false});
    Bounds3 region = a.bounds.empty() ? tape.bounds() : parseBoundsArg(a.bounds);
    if (!region.finite() || region.empty()) {
        throw InputError(
            a.scene +
            ": the scene is unbounded (a plane or a complement?); give the region with --bounds "
            "x0,y0,z0,x1,y1,z1");
    }
    SampleOptions o = sampleOptions(a);
    GridShape shape = gridShapeFor(region, o);
    double bytes = static_cast<double>(shape.vertexCount()) * sizeof(float);
    double have = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * sysconf(_SC_PAGE_SIZE);
    if (bytes > 0.4 * have) {
        throw InputError("--res " + std::to_string(a.resolution) + ": sampling needs " +
                         std::to_string(bytes / (1 << 30)) +
                         " GiB, more than this machine can hold; use a lower resolution");
    }
    auto t0 = std::chrono::steady_clock::now();
    Grid grid = sampleGrid(tape, region, o);
    auto t1 = std::chrono::steady_clock::now();
    saveGridFile(grid, a.output);
    auto t2 = std::chrono::steady_clock::now();
    size_t in = 0, out = 0, surf = 0;
    grid.blockCounts(in, out, surf);
    std::fprintf(
        stderr,
        "sdftrace bake: %dx%dx%d cells (voxel %.4g), %s, %.2f MiB, sample %.3f s, write %.3f s%s\n",
        shape.cells[0], shape.cells[1], shape.cells[2], shape.voxelSize,
        grid.kind() == GridKind::Dense ? "dense" : "sparse", grid.memoryBytes() / 1048576.0,
        std::chrono::duration<double>(t1 - t0).count(),
        std::chrono::duration<double>(t2 - t1).count(),
        grid.kind() == GridKind::Sparse
            ? (", blocks " + std::to_string(surf) + " surface / " + std::to_string(in) +
               " inside / " + std::to_string(out) + " outside")
                  .c_str()
            : "");
    return 0;
}

}  // namespace

void addBakeCommand(CLI::App& app, Action& action) {
    auto args = std::make_shared<BakeArgs>();
    CLI::App* cmd = app.add_subcommand(
        "bake",
        "Sample a scene's distance field, or bake a mesh's signed distance, into a grid file");
    cmd->add_option("input", args->scene,
                    "Scene file (JSON) or mesh (.obj, .ply, .stl, .off, .gltf, .glb)")
        ->required();
    cmd->add_option("-o,--output", args->output,
                    "Output grid (.sdfg or .vdb, docs/file-formats.md)")
        ->required();
    cmd->add_option("--method", args->method,
                    "Meshes: exact (closest points through an Embree BVH), jfa (jump flooding, "
                    "RTSDF §2.2) or danielsson (two-pass vector distance transform, Liktor §3.2)")
        ->capture_default_str();
    cmd->add_option("--jfa-variant", args->jfaVariant, "Jump flooding: plain, 1+jfa or jfa+2")
        ->check(CLI::IsMember({"plain", "1+jfa", "jfa+2"}))
        ->capture_default_str();
    cmd->add_flag(
        "--verify", args->verify,
        "Meshes: also bake exactly and report mean / p99 / max error in voxels (all samples "
        "and the narrow band) and the share of wrong signs");
    cmd->add_option("--sign", args->sign,
                    "Meshes: winding (generalized winding number, robust on open meshes) or parity "
                    "(ray-crossing parity, closed meshes)")
        ->check(CLI::IsMember({"winding", "parity"}))
        ->capture_default_str();
    cmd->add_option("--res", args->resolution, "Cells along the longest axis of the region")
        ->check(CLI::Range(8, 4096))
        ->capture_default_str();
    auto* dense = cmd->add_flag("--dense", args->dense, "Store every sample");
    auto* sparse =
        cmd->add_flag("--sparse", args->sparse, "Sparse block grid (default; Jamriška §3)");
    dense->excludes(sparse);
    cmd->add_option("--block", args->blockSize, "Sparse: cells per block edge")
        ->check(CLI::IsMember({4, 8}))
        ->capture_default_str();
    cmd->add_option("--band", args->band,
                    "Sparse: narrow band half-width in voxels (blocks farther away are dropped)")
        ->check(CLI::Range(2.0, 64.0))
        ->capture_default_str();
    cmd->add_option("--bounds", args->bounds,
                    "Region x0,y0,z0,x1,y1,z1 (default: the scene's bounds)");
    cmd->add_option("--threads", args->threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, 1024));
    cmd->callback([&action, args] { action = [args] { return runBake(*args); }; });
}

}  // namespace sdft::cli
