// sdftrace query mesh.obj points.npy -o result.npz [--sign S] [--closest] [--winding-number]
//   [--inside] | --rays directions.npy [--t-max T] | --sample surface|near|volume --count N
// Exact mesh distance queries at arbitrary points (query/mesh_query.h,
// docs/guide/10-mesh-queries.md): the SDF data pipeline without a bake, answers written as NumPy
// arrays or CSV.
#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>

#include "commands.h"
#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/exec/progress.h"
#include "sdftrace/io/mesh_io.h"
#include "sdftrace/io/npy_io.h"
#include "sdftrace/query/mesh_query.h"
#include "sdftrace/query/mesh_sampling.h"

namespace sdft::cli {

namespace {

struct QueryArgs {
    std::string mesh, points, output, rays;
    std::string sign = "winding";
    bool closest = false, winding = false, inside = false;
    double tMax = INFINITY;
    std::string sample;
    int64_t count = 0;
    uint64_t seed = 0;
    std::vector<double> sigmas;
    std::vector<double> bounds;
    bool float64 = false;
    int threads = 0;
    bool quiet = false;
};

template <class T>
NamedArray arrayOf(const std::string& name, size_t rows, size_t cols) {
    NamedArray a;
    a.name = name;
    a.kind = std::is_same_v<T, bool> ? 'b' : std::is_integral_v<T> ? 'i' : 'f';
    a.itemsize = sizeof(T);
    a.rows = rows;
    a.cols = cols;
    a.bytes.resize(rows * std::max<size_t>(cols, 1) * sizeof(T));
    return a;
}
template <class T>
T* dataOf(NamedArray& a) {
    return reinterpret_cast<T*>(a.bytes.data());
}

template <class T>
std::vector<T> convert(const std::vector<double>& v) {
    return std::vector<T>(v.begin(), v.end());
}

// The point queries, in T (float for float32 input or samples, double otherwise).
template <class T>
std::vector<NamedArray> queryPoints(const MeshQuery& q, const std::vector<T>& xyz, size_t n,
                                    const QueryArgs& a, std::vector<NamedArray> arrays) {
    const bool isSigned = a.sign != "none";
    MeshSign sign = MeshSign::Winding;
    if (isSigned) parseMeshSign(a.sign, sign);
    arrays.push_back(arrayOf<T>(isSigned ? "sdf" : "distance", n, 0));
    MeshQuery::PointOutputs out;
    out.distance = arrays.back().bytes.data();
    if (a.closest) {
        arrays.push_back(arrayOf<T>("closest", n, 3));
        arrays.push_back(arrayOf<int64_t>("face", n, 0));
        arrays.push_back(arrayOf<T>("barycentric", n, 3));
    }
    if (a.winding) arrays.push_back(arrayOf<T>("winding", n, 0));
    if (a.inside) arrays.push_back(arrayOf<bool>("inside", n, 0));
    // Taken once every array is in place (a moved NamedArray keeps its buffer, but be plain).
    for (NamedArray& arr : arrays) {
        if (arr.name == "sdf" || arr.name == "distance") out.distance = arr.bytes.data();
        if (arr.name == "closest") out.closest = arr.bytes.data();
        if (arr.name == "face") out.face = dataOf<int64_t>(arr);
        if (arr.name == "barycentric") out.bary = arr.bytes.data();
        if (arr.name == "winding") out.winding = arr.bytes.data();
        if (arr.name == "inside") out.inside = dataOf<bool>(arr);
    }
    MeshQuery::PointOptions o;
    o.signedDistance = isSigned;
    o.sign = sign;
    if (!a.quiet && stderrIsTerminal()) o.progress = "sdftrace query";
    q.queryPoints(xyz.data(), n, out, o);
    return arrays;
}

template <class T>
std::vector<NamedArray> castRays(const MeshQuery& q, const std::vector<T>& origins,
                                 const std::vector<T>& dirs, size_t n, const QueryArgs& a) {
    std::vector<NamedArray> arrays;
    arrays.push_back(arrayOf<T>("t", n, 0));
    arrays.push_back(arrayOf<int64_t>("face", n, 0));
    arrays.push_back(arrayOf<T>("barycentric", n, 2));
    arrays.push_back(arrayOf<T>("normal", n, 3));
    MeshQuery::RayOutputs out{arrays[0].bytes.data(), dataOf<int64_t>(arrays[1]),
                              arrays[2].bytes.data(), arrays[3].bytes.data()};
    q.castRays(origins.data(), dirs.data(), n, a.tMax, out,
               !a.quiet && stderrIsTerminal() ? "sdftrace query" : "");
    return arrays;
}

// Sampled points (and, for surface samples, their normals and faces) in T.
template <class T>
std::vector<NamedArray> sampled(const MeshQuery& q, const QueryArgs& a, std::vector<T>& xyz) {
    const size_t n = static_cast<size_t>(a.count);
    std::vector<NamedArray> arrays;
    arrays.push_back(arrayOf<T>("points", n, 3));
    T* p = dataOf<T>(arrays[0]);
    if (a.sample == "surface") {
        arrays.push_back(arrayOf<T>("normal", n, 3));
        arrays.push_back(arrayOf<int64_t>("face", n, 0));
        sampleSurface(q, n, a.seed, p, dataOf<T>(arrays[1]), dataOf<int64_t>(arrays[2]));
    } else if (a.sample == "near") {
        sampleNearSurface(q, n, a.sigmas.empty() ? defaultNearSurfaceSigmas(q) : a.sigmas, a.seed,
                          p);
    } else {
        auto [lo, hi] = q.bounds();
        if (a.bounds.empty()) {
            const double g = 0.05 * q.diagonal();
            lo = lo - Vec3d{g, g, g};
            hi = hi + Vec3d{g, g, g};
        } else {
            lo = {a.bounds[0], a.bounds[1], a.bounds[2]};
            hi = {a.bounds[3], a.bounds[4], a.bounds[5]};
        }
        sampleVolume(n, lo, hi, a.seed, p);
    }
    xyz.assign(p, p + 3 * n);
    return arrays;
}

int runQuery(const QueryArgs& a) {
    std::optional<tbb::global_control> threads;
    if (a.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, a.threads);
    if (a.points.empty() == a.sample.empty())
        throw InputError(a.points.empty()
                             ? "sdftrace query: give a points file or --sample (none given)"
                             : "sdftrace query: give a points file or --sample, not both");
    if (!a.rays.empty() && a.points.empty())
        throw InputError("sdftrace query: --rays needs a points file of ray origins");
    if (!a.sample.empty() && a.count <= 0)
        throw InputError("sdftrace query: --sample " + a.sample + " needs --count N > 0");
    if (!a.bounds.empty() && a.bounds.size() != 6)
        throw InputError("sdftrace query: --bounds: expected x0,y0,z0,x1,y1,z1");
    for (size_t i = 0; i < 3 && !a.bounds.empty(); ++i)
        if (!(a.bounds[i] <= a.bounds[i + 3]) || !std::isfinite(a.bounds[i]) ||
            !std::isfinite(a.bounds[i + 3]))
            throw InputError(
                "sdftrace query: --bounds: expected finite x0,y0,z0,x1,y1,z1 with "
                "each low corner <= its high one");
    const auto t0 = std::chrono::steady_clock::now();
    MeshReport report;
    TriangleMesh mesh = loadMesh(a.mesh, &report);
    std::vector<Vec3d> vertices;
    vertices.reserve(mesh.positions.size());
    for (Vec3 p : mesh.positions) vertices.push_back(toDouble(p));
    const MeshQuery q(std::move(vertices), std::move(mesh.triangles), a.mesh);
    const double loadSeconds = since(t0);
    const auto t1 = std::chrono::steady_clock::now();
    std::vector<NamedArray> arrays;
    size_t n = 0;
    if (!a.rays.empty()) {
        const PointTable o = readPointTable(a.points, 3), d = readPointTable(a.rays, 3);
        if (o.rows != d.rows)
            throw InputError(a.rays + ": " + std::to_string(d.rows) + " directions for " +
                             std::to_string(o.rows) + " origins in " + a.points +
                             "; expected one per origin");
        n = o.rows;
        if (o.single && d.single)
            arrays = castRays(q, convert<float>(o.values), convert<float>(d.values), n, a);
        else
            arrays = castRays(q, o.values, d.values, n, a);
    } else if (!a.points.empty()) {
        const PointTable p = readPointTable(a.points, 3);
        n = p.rows;
        if (p.single)
            arrays = queryPoints(q, convert<float>(p.values), n, a, {});
        else
            arrays = queryPoints(q, p.values, n, a, {});
    } else {
        n = static_cast<size_t>(a.count);
        // Points, answers (closest points and barycentrics at most) and the output's bytes.
        checkMemoryBudget(static_cast<double>(n) * (a.float64 ? 8 : 4) * 3 * 6,
                          "--count " + std::to_string(a.count), "the sampled points and answers",
                          "sample fewer points per run (--seed keeps runs apart)");
        if (a.float64) {
            std::vector<double> xyz;
            std::vector<NamedArray> s = sampled(q, a, xyz);
            arrays = queryPoints(q, xyz, n, a, std::move(s));
        } else {
            std::vector<float> xyz;
            std::vector<NamedArray> s = sampled(q, a, xyz);
            arrays = queryPoints(q, xyz, n, a, std::move(s));
        }
    }
    const double querySeconds = since(t1);
    const auto t2 = std::chrono::steady_clock::now();
    writeArrays(a.output, arrays);
    std::fprintf(stderr,
                 "sdftrace query: %s (%zu triangles%s) -> %s: %zu %s, mesh %.3f s, query %.3f s "
                 "(%.0f per second), write %.3f s\n",
                 a.mesh.c_str(), q.faces().size(), q.watertight() ? ", closed" : ", open",
                 a.output.c_str(), n, a.rays.empty() ? "points" : "rays", loadSeconds, querySeconds,
                 querySeconds > 0 ? n / querySeconds : 0.0, since(t2));
    return 0;
}

}  // namespace

void addQueryCommand(CLI::App& app, Action& action) {
    auto args = std::make_shared<QueryArgs>();
    CLI::App* cmd = app.add_subcommand(
        "query",
        "Exact distances, signs, closest points, winding numbers or ray hits of a mesh at "
        "points from a file (.npy or CSV) or sampled for learning; answers as .npz, .npy or "
        ".csv (docs/guide/10-mesh-queries.md)");
    cmd->add_option("mesh", args->mesh, "Mesh (.obj, .ply, .stl, .off, .gltf, .glb)")->required();
    cmd->add_option("points", args->points,
                    "N x 3 points (ray origins with --rays): .npy (float32 in, float32 out; "
                    "float64 or integers in, float64 out) or CSV (x,y,z per line; float64)");
    cmd->add_option("-o,--output", args->output,
                    ".npz (every array by name), .npy (one array) or .csv (columns)")
        ->required();
    cmd->add_option("--sign", args->sign,
                    "Sign of the distances: winding (generalized winding number with holes "
                    "spanned: robust on open scans), parity (ray crossings), pseudonormal "
                    "(closed manifold meshes), none (unsigned, array 'distance')")
        ->check(CLI::IsMember({"winding", "parity", "pseudonormal", "none"}))
        ->capture_default_str();
    cmd->add_flag("--closest", args->closest,
                  "Also the closest points ('closest'), their face ids ('face') and barycentric "
                  "coordinates ('barycentric')");
    cmd->add_flag("--winding-number", args->winding,
                  "Also the generalized winding numbers ('winding')");
    cmd->add_flag("--inside", args->inside, "Also inside flags by --sign ('inside', bool)");
    cmd->add_option("--rays", args->rays,
                    "Cast rays from the points along these N x 3 directions (.npy or CSV): "
                    "'t' (inf: miss), 'face' (-1: miss), 'barycentric' (u, v), 'normal'");
    cmd->add_option("--t-max", args->tMax, "With --rays: hits beyond t are misses")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--sample", args->sample,
                    "Sample the points instead of reading them: surface (by area, with 'normal' "
                    "and 'face'), near (DeepSDF: surface points plus Gaussian noise of --sigma), "
                    "volume (uniform in --bounds); written as 'points' beside the answers")
        ->check(CLI::IsMember({"surface", "near", "volume"}));
    cmd->add_option("--count", args->count, "With --sample: how many points")
        ->check(CLI::Range(int64_t{1}, int64_t{1} << 40));
    cmd->add_option("--seed", args->seed, "With --sample: the random seed (same seed, same points)")
        ->capture_default_str();
    cmd->add_option("--sigma", args->sigmas,
                    "With --sample near: Gaussian widths in mesh units, point i uses width "
                    "i mod count (default: DeepSDF's 0.05 and 0.0158 times half the box's "
                    "diagonal)")
        ->delimiter(',')
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--bounds", args->bounds,
                    "With --sample volume: x0,y0,z0,x1,y1,z1 (default: the mesh's box grown by 5 % "
                    "of its diagonal)")
        ->delimiter(',');
    cmd->add_flag("--float64", args->float64, "With --sample: float64 points and answers");
    cmd->add_option("--threads", args->threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, 1024));
    cmd->add_flag("-q,--quiet", args->quiet, "No progress on stderr (the summary line stays)");
    cmd->callback([&action, args] { action = [args] { return runQuery(*args); }; });
}

}  // namespace sdft::cli
