// sdftrace bake scene.json --res N -o field.sdfg [--dense | --sparse] [--block 4|8] [--band W]
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <numeric>
#include <optional>

#include "commands.h"
#include "sdftrace/bake/bake_options.h"
#include "sdftrace/bake/exact_bake.h"
#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/bake/texture_coords.h"
#include "sdftrace/bake/verify_bake.h"
#include "sdftrace/cluster/distributed_bake.h"
#include "sdftrace/cluster/work_farm.h"
#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/gpu/device.h"
#include "sdftrace/gpu/gpu_device.h"
#include "sdftrace/io/atomic_file.h"
#include "sdftrace/io/grid_file.h"
#include "sdftrace/io/mesh_file.h"
#include "sdftrace/io/mesh_io.h"
#include "sdftrace/io/sdfg_io.h"
#include "sdftrace/scene/animated_scene.h"
#include "sdftrace/scene/parse_scene.h"

namespace sdft::cli {

namespace {

struct BakeArgs {
    std::string scene;
    std::optional<double> time;  // --time: the instant of an animated scene
    std::string output;
    // The bake option table's flags (bake/bake_options.h), one per row in its order, and the
    // options they make (runBake fills `bake`).
    struct OptionFlag {
        std::string text;
        bool value = false;  // Bool rows: the flag, and the one that sets false ("--sparse")
        bool falseValue = false;
        CLI::Option* cli = nullptr;
        CLI::Option* falseCli = nullptr;
    };
    std::vector<OptionFlag> options;
    MeshBakeOptions bake;
    std::string bounds;
    bool quiet = false;
    bool verify = false;
    bool listOptions = false;
    int threads = 0;
    std::string device = "cpu";  // cpu, cuda, auto
    std::string texcoords;       // "", sphere, cylinder
    std::string texcoordCenter, texcoordAxis;
    const CLI::App* command = nullptr;  // to ask which flags were given
};

bool given(const BakeArgs& a, const char* flag) {
    const CLI::Option* o = a.command ? a.command->get_option_no_throw(flag) : nullptr;
    return o && o->count() > 0;
}

// A flag that does nothing for this input is an error, not silently ignored.
void rejectGiven(const BakeArgs& a, std::initializer_list<const char*> flags,
                 const std::string& why) {
    for (const char* flag : flags)
        if (given(a, flag)) throw InputError(std::string(flag) + ": " + why);
}

void rejectFlagsThatDoNotApply(const BakeArgs& a, bool mesh) {
    const MeshBakeOptions& o = a.bake;
    const bool dense = o.sampling.kind == GridKind::Dense;
    if (mesh) {
        rejectGiven(a, {"--bounds"},
                    "applies to scene files only (a mesh's grid covers the mesh's bounds)");
        if (o.method != MeshBakeMethod::Rtsdf)
            rejectGiven(a, {"--rays", "--mask"}, "applies to --method rtsdf only");
        if (o.method != MeshBakeMethod::JumpFlood)
            rejectGiven(a, {"--jfa-variant"}, "applies to --method jfa only");
        if (o.sign != SignMethod::BetaShell)
            rejectGiven(a, {"--beta"}, "applies to --sign beta only");
        if (o.method != MeshBakeMethod::Exact || !dense)
            rejectGiven(a, {"--closest"}, "applies to --method exact with --dense only");
    } else {
        const std::string why =
            "applies to meshes only; " + a.scene + " is a scene file, sampled from its own field";
        for (const BakeOption& option : bakeOptions())
            if (option.meshOnly) rejectGiven(a, {option.mainFlag().c_str()}, why);
        rejectGiven(a, {"--device"}, why);
    }
    if (dense) rejectGiven(a, {"--block", "--band"}, "applies to sparse grids only (--dense)");
    if (a.texcoords.empty())
        rejectGiven(a, {"--texcoord-center", "--texcoord-axis"}, "needs --texcoords");
}

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

// The bake options from the table's flags: each given one parsed by its row (CLI11 checked the
// text against the same row while parsing), the others at the table's default.
MeshBakeOptions bakeOptionsFromFlags(const BakeArgs& a) {
    MeshBakeOptions o;
    const auto table = bakeOptions();
    for (size_t i = 0; i < table.size(); ++i) {
        const BakeArgs::OptionFlag& flag = a.options[i];
        if (flag.falseCli && flag.falseCli->count() > 0) table[i].set(o, 0);
        if (!flag.cli || flag.cli->count() == 0) continue;
        if (table[i].type == OptionType::Bool)
            table[i].set(o, 1);
        else
            setBakeOption(o, table[i].key, flag.text, table[i].mainFlag());
    }
    o.sampling.threads = a.threads;
    o.progress = !a.quiet;
    return o;
}

// Refuses a bake whose arrays would not fit the memory budget, naming the flag.
void checkMemory(double bytes, int resolution) {
    checkMemoryBudget(bytes, "--res " + std::to_string(resolution), "the bake's arrays",
                      "use a lower resolution or a sparse exact bake");
}

// A distributed bake's share on each of `ranks` ranks: `shared` bytes split among them, `fixed`
// on every rank (the mesh and its trees). Refused with the ranks the budget would need.
void checkRankMemory(double shared, double fixed, int ranks, int resolution) {
    const double budget = memoryBudgetBytes();
    std::string advice = "use a lower resolution";
    if (budget > fixed)
        advice += " or about " +
                  std::to_string(static_cast<long long>(std::ceil(shared / (budget - fixed)))) +
                  " ranks with this budget";
    checkMemoryBudget(shared / ranks + fixed, "--res " + std::to_string(resolution),
                      "the bake's arrays on each of " + std::to_string(ranks) + " ranks", advice);
}

double seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
}

// Liktor 2008, §5.5.2: texture coordinates by particles traced along the gradient of `field`.
// `stopLevel`: TexcoordOptions::stopLevel (a narrow band's inner level for mesh grids).
void addTexcoords(const BakeArgs& a, Grid& grid, const std::function<float(Vec3)>& field,
                  float stopLevel = INFINITY) {
    if (a.texcoords.empty()) return;
    TexcoordOptions o;
    parseTexcoordKind(a.texcoords, o.helper);  // checked by the flag
    o.stopLevel = stopLevel;
    if (!a.texcoordCenter.empty()) {
        const Vec3Arg c = parseVec3Arg("--texcoord-center", a.texcoordCenter);
        o.center = {c.x, c.y, c.z};
        o.autoCenter = false;
    }
    if (!a.texcoordAxis.empty()) {
        const Vec3Arg v = parseVec3Arg("--texcoord-axis", a.texcoordAxis);
        o.axis = {v.x, v.y, v.z};
        if (!(length(o.axis) > 0) || !std::isfinite(length(o.axis)))
            throw InputError("--texcoord-axis " + a.texcoordAxis + ": expected a non-zero vector");
    }
    o.threads = a.threads;
    const auto t0 = std::chrono::steady_clock::now();
    const TexcoordStats st = bakeTexcoords(grid, field, o);
    std::fprintf(
        stderr,
        "sdftrace bake: texture coordinates (%s helper, centre %.3g,%.3g,%.3g, radius "
        "%.3g): %zu particles, %.1f steps and %.0f field evaluations each, %zu stopped where "
        "the field stops rising, %zu at the band's level, %zu unfinished, %zu samples off the band "
        "projected, %.3f s\n",
        a.texcoords.c_str(), st.center.x, st.center.y, st.center.z, st.radius, st.particles,
        st.meanSteps, st.fieldEvaluations, st.ridges, st.atLevel, st.unfinished, st.projected,
        seconds(t0, std::chrono::steady_clock::now()));
}

void printVerify(const char* method, const BakeVerification& v) {
    auto line = [&](const char* where, const BakeError& e) {
        if (e.count == 0) return;
        std::fprintf(stderr,
                     "sdftrace bake: verify %s, %s (%zu samples): mean %.4f, p99 %.4f, max %.4f "
                     "voxels\n",
                     method, where, e.count, e.mean, e.p99, e.max);
    };
    line("stored samples", v.all);
    line("narrow band", v.band);
    std::fprintf(stderr,
                 "sdftrace bake: verify %s: %.4f%% of %zu vertices with the wrong sign (%.4f%% "
                 "beyond half a voxel of the surface)\n",
                 method, 100.0 * v.wrongSignShare(), v.vertices,
                 v.vertices ? 100.0 * static_cast<double>(v.wrongSignsFar) / v.vertices : 0.0);
}

// A scene's grid against the scene's own field f/L: at the vertices, and at cell centres where
// the trilinear reconstruction stands in for the field.
void printFieldVerify(const FieldVerification& v) {
    printVerify("field, vertices", v.vertices);
    if (v.centres.count)
        std::fprintf(stderr,
                     "sdftrace bake: verify field, cell centres in the band (%zu, trilinear "
                     "reconstruction): mean %.4f, p99 %.4f, max %.4f voxels; %.4f%% of %zu centres "
                     "with the wrong sign\n",
                     v.centres.count, v.centres.mean, v.centres.p99, v.centres.max,
                     v.signedCentres ? 100.0 * v.wrongSignCentres / v.signedCentres : 0.0,
                     v.signedCentres);
}

// The mesh bake's options from the flags (validated).
MeshBakeOptions meshBakeOptions(const BakeArgs& a) {
    MeshBakeOptions o = a.bake;
    validateMeshBakeOptions(o);
    return o;
}

// "load 0.123 s, <stage> 0.456 s, ...": the summary's list of phases.
std::string stagesText(double loadSeconds, const std::vector<BakeStage>& stages) {
    std::string text = "load " + std::to_string(loadSeconds).substr(0, 5) + " s";
    for (const BakeStage& st : stages) {
        char one[96];
        std::snprintf(one, sizeof one, ", %s %.3f s", st.name.c_str(), st.seconds);
        text += one;
    }
    return text;
}

// The summary lines of a finished mesh bake (t0: start, t1: loaded, t2: baked, t3 / t4: around
// the write).
void printMeshBakeSummary(const BakeArgs& a, const MeshBakeResult& r,
                          const std::array<std::chrono::steady_clock::time_point, 5>& t) {
    const GridShape& shape = r.grid.shape();
    std::string stages = stagesText(seconds(t[0], t[1]), r.stages);
    char tail[96];
    std::snprintf(tail, sizeof tail, ", write %.3f s; total %.3f s", seconds(t[3], t[4]),
                  seconds(t[0], t[4]) - seconds(t[2], t[3]));
    stages += tail;
    if (!r.details.empty())
        std::fprintf(stderr, "sdftrace bake: %s: %s\n", meshBakeMethodName(a.bake.method),
                     r.details.c_str());
    size_t in = 0, out = 0, surf = 0;
    if (r.grid.kind() == GridKind::Sparse) r.grid.blockCounts(in, out, surf);
    std::fprintf(stderr,
                 "sdftrace bake: %s, %dx%dx%d cells (voxel %.4g), %s%s, grid %.2f MiB, peak "
                 "memory %.0f MiB\nsdftrace bake: %s\n",
                 meshBakeMethodName(a.bake.method), shape.cells[0], shape.cells[1], shape.cells[2],
                 shape.voxelSize, r.grid.kind() == GridKind::Dense ? "dense" : "sparse",
                 r.grid.kind() == GridKind::Sparse
                     ? (" (" + std::to_string(surf) + " surface / " + std::to_string(in) +
                        " inside / " + std::to_string(out) + " outside blocks)")
                           .c_str()
                     : "",
                 r.grid.memoryBytes() / 1048576.0, peakResidentMiB(), stages.c_str());
}

// The summary lines of a bake every rank wrote (bakeExactToSdfg).
void printDistributedBakeSummary(const BakeArgs& a, const DistributedBakeSummary& r,
                                 double loadSeconds) {
    const GridShape& shape = r.shape;
    const std::string stages = stagesText(loadSeconds, r.stages);
    double total = loadSeconds;  // rank 0's phases are within the slabs' time
    for (const BakeStage& st : r.stages)
        if (st.name.rfind("rank 0 ", 0) != 0) total += st.seconds;
    std::fprintf(stderr, "sdftrace bake: %s: %s\n", meshBakeMethodName(a.bake.method),
                 r.details.c_str());
    std::fprintf(stderr,
                 "sdftrace bake: %s, %dx%dx%d cells (voxel %.4g), sparse (%llu surface / %llu "
                 "inside / %llu outside blocks), file %.2f MiB, peak memory %.0f MiB (the "
                 "largest of any rank)\nsdftrace bake: %s; total %.3f s\n",
                 meshBakeMethodName(a.bake.method), shape.cells[0], shape.cells[1], shape.cells[2],
                 shape.voxelSize, static_cast<unsigned long long>(r.surface),
                 static_cast<unsigned long long>(r.inside),
                 static_cast<unsigned long long>(r.outside), r.fileBytes / 1048576.0, r.peakMiB,
                 stages.c_str(), total);
}

// Whether the mesh bakes on the GPU: cuda insists (an error names what the GPU lacks, before
// anything is loaded), auto takes it where a GPU is present and bakes the method, else says why
// not on stderr. Under mpirun the ranks that bake choose as one process does (a method the GPU
// bakes runs on rank 0 alone, on its GPU); the others do not bake.
bool bakeOnGpu(const BakeArgs& a, const MeshBakeOptions& o, bool bakesHere) {
    Device d = Device::Cpu;
    parseDevice(a.device, d);  // CLI11 checked the name
    if (!bakesHere) return false;
    const DeviceChoice c = chooseBakeDevice(d, o, "--device " + a.device);
    if (d == Device::Auto && !c.gpu && !a.quiet)
        std::fprintf(stderr, "sdftrace bake: --device auto: baking on the CPU (%s)\n",
                     c.why.c_str());
    return c.gpu;
}

// Each rank checks its own budget before any work: its share of a bake split across the ranks
// (`across`), else the whole bake's.
void checkBakeMemory(const BakeArgs& a, const MeshBakeOptions& o, const TriangleMesh& mesh,
                     const Communicator& comm, bool across) {
    const GridShape shape = gridShapeFor(mesh.bounds(), o.sampling);
    const bool verify = a.verify && comm.root();
    const int resolution = a.bake.sampling.resolution;
    if (!across) return checkMemory(meshBakeBytes(mesh, shape, o, verify, 1.0), resolution);
    const double fixed = meshBakeBytes(mesh, shape, o, verify, 0);
    checkRankMemory(meshBakeBytes(mesh, shape, o, verify, 1) - fixed, fixed, comm.size(),
                    resolution);
    checkMeshBake(mesh, o, 1.0 / comm.size());
}

// A mesh file, by any method of mesh_bake.h; --verify compares with the exact bake. Under mpirun
// the sparse exact bake runs on every rank, one slab each (cluster/distributed_bake.h); the other
// methods run on rank 0.
int bakeMesh(const BakeArgs& a, Communicator& comm) {
    MeshBakeOptions o;
    auto t0 = std::chrono::steady_clock::now();
    MeshReport report;
    TriangleMesh mesh;
    bool across = false, gpu = false;
    together(comm, [&] {
        o = meshBakeOptions(a);
        across = comm.distributed() && o.method == MeshBakeMethod::Exact &&
                 o.sampling.kind == GridKind::Sparse;
        // Ranks on one machine take its GPUs in turn, as renders do.
        if (comm.distributed() && a.device != "cpu") useGpuOfLocalRank(comm.localRank());
        gpu = bakeOnGpu(a, o, comm.root() || across);
        if (comm.distributed() && !across && !comm.root()) return;  // rank 0 bakes alone
        mesh = loadMesh(a.scene, &report);
        checkBakeMemory(a, o, mesh, comm, across);
    });
    // A .sdfg is written by every rank, none holding the whole grid; other outputs, --verify and
    // --texcoords need the grid assembled on rank 0.
    if (across && std::filesystem::path(a.output).extension() == ".sdfg" && !a.verify &&
        a.texcoords.empty()) {
        if (comm.root())
            std::fprintf(stderr, "sdftrace bake: %s: %s\n", a.scene.c_str(),
                         report.summary().c_str());
        const auto t1 = std::chrono::steady_clock::now();
        const DistributedBakeSummary r =
            bakeExactToSdfg(comm, mesh, o, a.output, SdfgWriteOptions{}.level);
        if (comm.root()) printDistributedBakeSummary(a, r, seconds(t0, t1));
        return 0;
    }
    if (comm.distributed() && !comm.root()) {
        if (across) serveRounds(comm, [&](const Bytes& c) { return exactSlabWorker(mesh, o, c); });
        return 0;
    }
    if (comm.distributed() && !across) {
        comm.setOthersDone();
        std::fprintf(stderr,
                     "sdftrace bake: --method %s%s runs on rank 0 alone (the sparse exact bake is "
                     "the one split across ranks)\n",
                     meshBakeMethodName(o.method),
                     o.sampling.kind == GridKind::Dense ? " --dense" : "");
    }
    std::fprintf(stderr, "sdftrace bake: %s: %s\n", a.scene.c_str(), report.summary().c_str());
    auto t1 = std::chrono::steady_clock::now();
    MeshBakeResult r;
    if (across) {
        WorkFarm farm(comm);
        r = bakeExactAcross(farm, mesh, o);
        farm.end();
    } else {
        r = bakeMeshOn(gpu, mesh, o);
    }
    auto t2 = std::chrono::steady_clock::now();
    if (a.verify) {
        MeshBvh bvh(mesh);
        std::vector<float> exact = bakeExactSamples(bvh, r.grid.shape(), SignMethod::WindingNumber,
                                                    a.threads, nullptr, true);
        printVerify(meshBakeMethodName(o.method), verifyBake(r.grid, exact, o.sampling.bandVoxels));
    }
    if (!a.texcoords.empty()) {
        const GridView v = r.grid.view();
        // Particles follow the grid's reconstruction, a distance up to a voxel short of the band
        // where the sparse grid clamps it.
        const float stop = r.grid.kind() == GridKind::Sparse
                               ? (o.sampling.bandVoxels - 1) * r.grid.shape().voxelSize
                               : static_cast<float>(INFINITY);
        addTexcoords(
            a, r.grid, [v](Vec3 p) { return v.sample(p); }, stop);
    }
    auto t3 = std::chrono::steady_clock::now();
    saveGridFile(r.grid, a.output);
    printMeshBakeSummary(a, r, {t0, t1, t2, t3, std::chrono::steady_clock::now()});
    return 0;
}

int runBake(const BakeArgs& args) {
    if (args.listOptions) {
        std::fputs(bakeOptionsMarkdown().c_str(), stdout);
        return 0;
    }
    if (args.scene.empty())
        throw InputError("input: missing; give a scene file (JSON) or a mesh to bake");
    if (args.output.empty())
        throw InputError("--output: missing; give the grid file to write (.sdfg or .vdb)");
    Communicator& comm = Communicator::world();
    BakeArgs a = args;
    if (comm.distributed()) {
        if (!a.threads) a.threads = defaultRankThreads(comm);
        if (!comm.root()) a.quiet = true;
    }
    together(comm, [&] {
        a.bake = bakeOptionsFromFlags(a);
        if (!isGridFile(a.output))
            throw InputError("--output " + a.output + ": accepted extensions: .sdfg, .vdb");
        if (comm.root()) checkWritablePath(a.output, "--output");  // rank 0 writes it
        if (!a.texcoords.empty() && std::filesystem::path(a.output).extension() != ".sdfg") {
            throw InputError(
                "--texcoords: texture coordinates are stored in .sdfg files only, not " + a.output);
        }
        rejectFlagsThatDoNotApply(a, isMeshFile(a.scene));
        if (a.time && isMeshFile(a.scene))
            throw InputError("--time: " + a.scene +
                             " is a mesh; --time picks the instant of a scene file with keyframes");
    });
    if (isMeshFile(a.scene)) return bakeMesh(a, comm);
    // A scene file's field is sampled on rank 0.
    if (comm.distributed()) {
        if (!comm.root()) return 0;
        comm.setOthersDone();
        std::fprintf(stderr, "sdftrace bake: a scene file is sampled on rank 0 alone\n");
    }
    AssetCache cache;
    Scene scene =
        a.time ? AnimatedScene::fromFile(a.scene).at(*a.time, cache) : parseSceneFile(a.scene);
    // The field's definition (no culling): sampled values should be the field, not a looser bound.
    Tape tape = compileTape(scene.root, {.boundsCulling = false});
    Bounds3 region = a.bounds.empty() ? tape.bounds() : parseBoundsArg(a.bounds);
    if (!region.finite() || region.empty()) {
        throw InputError(
            a.scene +
            ": the scene is unbounded (a plane or a complement?); give the region with --bounds "
            "x0,y0,z0,x1,y1,z1");
    }
    const SampleOptions& o = a.bake.sampling;
    GridShape shape = gridShapeFor(region, o);
    checkMemory(static_cast<double>(shape.vertexCount()) * sizeof(float), o.resolution);
    auto t0 = std::chrono::steady_clock::now();
    Grid grid = sampleGrid(tape, region, o);
    addTexcoords(a, grid, [&tape](Vec3 p) { return tape.eval(p); });
    auto t1 = std::chrono::steady_clock::now();
    if (a.verify) printFieldVerify(verifyAgainstField(grid, tape, o.bandVoxels, a.threads));
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

// The bake option table's flags (bake_options.h): each row's flag, checked by its row while
// CLI11 parses, with the row's default and doc in --help.
void addOptionFlags(CLI::App* cmd, BakeArgs& args) {
    const auto table = bakeOptions();
    args.options.resize(table.size());  // fixed from here on: CLI11 keeps pointers into it
    CLI::Option_group* grid = cmd->add_option_group("Grid", "The grid every bake makes");
    CLI::Option_group* mesh = cmd->add_option_group("Mesh", "How a mesh's distances are computed");
    for (size_t i = 0; i < table.size(); ++i) {
        const BakeOption& o = table[i];
        BakeArgs::OptionFlag& arg = args.options[i];
        CLI::Option_group* group = o.meshOnly ? mesh : grid;
        const std::string help = std::string(o.doc) + " [" + o.defaultText() + "]";
        if (o.type == OptionType::Bool) {  // --dense or --sparse, not both
            arg.cli = group->add_flag(o.mainFlag(), arg.value, help);
            arg.falseCli = group->add_flag(o.falseFlag, arg.falseValue,
                                           std::string("the opposite of ") + o.mainFlag());
            arg.cli->excludes(arg.falseCli);
            continue;
        }
        CLI::Validator valid(
            [&o](std::string& text) {
                double v = 0;
                return o.parse(text, v);
            },
            o.type == OptionType::Choice ? o.value().choiceList() : o.accepted());
        const char* type = o.type == OptionType::Choice ? "NAME"
                           : o.type == OptionType::Int  ? "INT"
                                                        : "FLOAT";
        arg.cli = group->add_option(o.flags, arg.text, help)->type_name(type)->check(valid);
    }
}

}  // namespace

void addBakeCommand(CLI::App& app, Action& action) {
    auto args = std::make_shared<BakeArgs>();
    CLI::App* cmd = app.add_subcommand(
        "bake",
        "Sample a scene's distance field, or bake a mesh's signed distance, into a grid file");
    cmd->add_option("input", args->scene,
                    "Scene file (JSON) or mesh (.obj, .ply, .stl, .off, .gltf, .glb); required");
    cmd->add_option("-o,--output", args->output,
                    "Output grid (.sdfg or .vdb, docs/file-formats.md); required");
    addOptionFlags(cmd, *args);
    cmd->add_flag(
        "--verify", args->verify,
        "Also report mean / p99 / max error in voxels and the share of wrong signs: meshes "
        "against an exact bake (all samples and the narrow band); scene files against the "
        "scene's own field f/L (at the vertices, and at cell centres through the trilinear "
        "reconstruction)");
    cmd->add_option("--time", args->time,
                    "Bake a scene file at this time in seconds (its keyframed values, "
                    "docs/scene-format.md \"Animation\"; default: the animation's start)")
        ->check(CLI::Range(-1e9, 1e9));
    cmd->add_flag("-q,--quiet", args->quiet, "No progress on stderr (the summary lines stay)");
    cmd->add_option("--bounds", args->bounds,
                    "Region x0,y0,z0,x1,y1,z1 (default: the scene's bounds)");
    cmd->add_option("--threads", args->threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, 1024));
    cmd->add_option("--device", args->device,
                    "Meshes: where the bake runs: cpu; cuda (the GPU: --method jfa or rtsdf, "
                    "signs by winding, or beta for jfa; an LBVH built on the GPU for rtsdf's "
                    "rays); auto (the GPU where one is present and bakes the method, else the "
                    "CPU)")
        ->check(CLI::IsMember({"cpu", "cuda", "auto"}))
        ->capture_default_str();
    cmd->add_option("--texcoords", args->texcoords,
                    "Also store texture coordinates (.sdfg): particles traced along the gradient "
                    "to an enclosing sphere or cylinder helper (Liktor §4.2.2, §5.5.2)")
        ->check(CLI::IsMember({"sphere", "cylinder"}));
    cmd->add_option("--texcoord-center", args->texcoordCenter,
                    "The helper's centre x,y,z (default: the centre of the surface's bounds)");
    cmd->add_option("--texcoord-axis", args->texcoordAxis,
                    "The helper's axis x,y,z: the sphere's poles, the cylinder's axis (default "
                    "0,1,0)");
    cmd->add_flag("--list-options", args->listOptions,
                  "Print every bake option (scene key and Python keyword, flag, default, accepted "
                  "values) as a Markdown table and exit");
    args->command = cmd;
    cmd->callback([&action, args] { action = [args] { return runBake(*args); }; });
}

}  // namespace sdft::cli
