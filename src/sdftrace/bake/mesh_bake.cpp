#include "sdftrace/bake/mesh_bake.h"

#include <chrono>
#include <cstdio>

#include "sdftrace/bake/danielsson.h"
#include "sdftrace/bake/exact_bake.h"
#include "sdftrace/bake/seed_signs.h"
#include "sdftrace/bake/separable_edt.h"
#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/exec/thread_arena.h"

namespace sdft {

const char* meshBakeMethodName(MeshBakeMethod m) {
    switch (m) {
        case MeshBakeMethod::Exact:
            return "exact";
        case MeshBakeMethod::JumpFlood:
            return "jfa";
        case MeshBakeMethod::Danielsson:
            return "danielsson";
        case MeshBakeMethod::SeparableEdt:
            return "edt";
        case MeshBakeMethod::Rtsdf:
            return "rtsdf";
    }
    return "?";
}

bool parseMeshBakeMethod(const std::string& name, MeshBakeMethod& out) {
    for (MeshBakeMethod m :
         {MeshBakeMethod::Exact, MeshBakeMethod::JumpFlood, MeshBakeMethod::Danielsson,
          MeshBakeMethod::SeparableEdt, MeshBakeMethod::Rtsdf}) {
        if (name == meshBakeMethodName(m)) {
            out = m;
            return true;
        }
    }
    return false;
}

void validateMeshBakeOptions(const MeshBakeOptions& o) {
    const bool seedBased = o.method == MeshBakeMethod::JumpFlood ||
                           o.method == MeshBakeMethod::Danielsson ||
                           o.method == MeshBakeMethod::SeparableEdt;
    if (!seedBased && o.sign != SignMethod::WindingNumber && o.sign != SignMethod::RayParity) {
        throw InputError(std::string("--sign ") +
                         (o.sign == SignMethod::FloodFill ? "flood" : "beta") + ": method " +
                         meshBakeMethodName(o.method) +
                         " accepts winding or parity (flood and beta need a voxelized surface: "
                         "jfa, danielsson, edt)");
    }
}

namespace {}  // namespace

std::string exactBakeDetails(const ExactBakeStats& st, const MeshBakeOptions& o,
                             const GridShape& shape) {
    const SampleOptions& so = o.sampling;
    char distances[160], line[400];
    if (so.kind == GridKind::Dense && o.closest == ClosestPoints::Transform) {
        std::snprintf(distances, sizeof distances,
                      "closest point transform: %zu rows, %zu distance evaluations (%.1f per "
                      "vertex)",
                      st.transformRows, st.transformEvaluations,
                      double(st.transformEvaluations) / double(shape.vertexCount()));
    } else {
        std::snprintf(
            distances, sizeof distances, "%zu %s", st.distanceQueries,
            so.kind == GridKind::Sparse ? "vertices within the band" : "distance queries");
    }
    std::snprintf(line, sizeof line, "%s, %zu sign evaluations (%s), %zu closing-film sums",
                  distances, st.signEvaluations, signMethodName(o.sign), st.filmSums);
    return line;
}

namespace {

// Exact distances: the narrow band (sparse) or the closest point transform / BVH (dense).
void bakeExact(const TriangleMesh& mesh, const MeshBakeOptions& o, const GridShape& shape,
               MeshBakeResult& r, StageClock& clock) {
    const SampleOptions& so = o.sampling;
    ExactBakeStats st;
    if (so.kind == GridKind::Sparse) {
        r.grid = bakeExactSparse(mesh, shape, so.blockSize, so.bandVoxels, o.sign, so.threads, &st,
                                 o.progress);
        r.stages.insert(r.stages.end(), st.phases.begin(), st.phases.end());
        clock.restart();
    } else {
        MeshBvh bvh(mesh);
        clock.mark("bvh");
        std::vector<float> exact =
            bakeExactSamples(bvh, shape, o.sign, so.threads, &st, o.progress, o.closest);
        r.stages.insert(r.stages.end(), st.phases.begin(), st.phases.end());
        clock.restart();
        r.grid = Grid::dense(shape, std::move(exact));
        clock.mark("grid");
    }
    r.details = exactBakeDetails(st, o, shape);
}

// RTSDF §2.1-2.3: a jump-flooded coarse field, refined by rays where it is near the surface.
std::vector<float> bakeRtsdf(const TriangleMesh& mesh, const MeshBakeOptions& o,
                             const GridShape& shape, MeshBakeResult& r, StageClock& clock) {
    MeshBvh bvh(mesh);
    clock.mark("bvh");
    RtsdfOptions ro = o.rtsdf;
    ro.coarseSign = o.sign;
    RtsdfStats st;
    std::vector<float> samples = bakeRtsdfSamples(mesh, bvh, shape, ro, o.sampling.threads, &st);
    r.stages.push_back({"coarse jfa", st.coarseSeconds});
    r.stages.push_back({"rays", st.raySeconds});
    clock.restart();
    char line[400];
    std::snprintf(line, sizeof line,
                  "%zu vertices refined by %d rays each (%zu rays), %zu with no hit", st.refined,
                  ro.rays, st.rays, st.missed);
    r.details = line;
    return samples;
}

// Seeds on the surface spread by jump flooding (RTSDF §2.2), Danielsson's sweeps (Liktor §3.2)
// or the separable EDT, then signed.
std::vector<float> bakeFromSeeds(const TriangleMesh& mesh, const MeshBakeOptions& o,
                                 const GridShape& shape, MeshBakeResult& r, StageClock& clock) {
    const SampleOptions& so = o.sampling;
    const int threads = so.threads;
    SurfaceSeeds seeds = seedSurfaceVertices(mesh, shape, threads);
    clock.mark("seeds");
    std::vector<Vec3> points;
    if (o.method == MeshBakeMethod::JumpFlood) {
        JfaStats st;
        points = jumpFlood(shape, seeds.point, o.jfaVariant, threads, &st);
        std::string passes;
        for (size_t i = 0; i < st.offsets.size(); ++i) {
            char one[48];
            std::snprintf(one, sizeof one, "%s%d: %.0f ms", i ? ", " : "", st.offsets[i],
                          st.passSeconds[i] * 1e3);
            passes += one;
        }
        r.details = std::to_string(st.offsets.size()) + " passes (offset: time) " + passes;
        clock.mark("jump flooding");
    } else if (o.method == MeshBakeMethod::Danielsson) {
        points = danielssonTransform(shape, seeds.point);
        clock.mark("danielsson sweeps");
    } else {
        points = separableEdt(shape, seeds.point, threads);
        clock.mark("separable edt");
    }
    std::vector<float> samples = distancesToPoints(shape, points, threads);
    std::unique_ptr<MeshBvh> bvh;
    if (o.sign == SignMethod::RayParity) bvh = std::make_unique<MeshBvh>(mesh);
    if (so.kind == GridKind::Sparse) {
        signDistancesSparse(samples, mesh, bvh.get(), shape, seeds, o.sign, o.betaVoxels,
                            so.blockSize, so.bandVoxels, threads);
    } else {
        signDistances(samples, mesh, bvh.get(), shape, seeds, o.sign, o.betaVoxels, threads);
    }
    clock.mark(std::string("signs (") + signMethodName(o.sign) + ")");
    return samples;
}

MeshBakeResult bakeInArena(const TriangleMesh& mesh, const MeshBakeOptions& o) {
    const SampleOptions& so = o.sampling;
    const GridShape shape = o.shape ? *o.shape : gridShapeFor(mesh.bounds(), so);
    MeshBakeResult r;
    StageClock clock(r.stages);
    if (o.method == MeshBakeMethod::Exact) {
        bakeExact(mesh, o, shape, r, clock);
        return r;
    }
    std::vector<float> samples = o.method == MeshBakeMethod::Rtsdf
                                     ? bakeRtsdf(mesh, o, shape, r, clock)
                                     : bakeFromSeeds(mesh, o, shape, r, clock);
    finishMeshBake(shape, std::move(samples), so, r, clock,
                   o.method == MeshBakeMethod::Rtsdf ? o.rtsdf.history : nullptr);
    return r;
}

}  // namespace

void finishMeshBake(const GridShape& shape, std::vector<float> samples, const SampleOptions& so,
                    MeshBakeResult& r, StageClock& clock, const RtsdfHistory* history) {
    if (so.kind == GridKind::Dense) {
        r.grid = Grid::dense(shape, std::move(samples));
    } else if (history) {
        const Grid* last = history->grid.get();
        const GridShape& ls = last ? last->shape() : shape;
        if (last && last->isComplete() && last->blockSize() == so.blockSize &&
            last->completeBand() == so.bandVoxels * shape.voxelSize &&
            ls.voxelSize == shape.voxelSize && ls.origin.x == shape.origin.x &&
            ls.origin.y == shape.origin.y && ls.origin.z == shape.origin.z &&
            std::equal(ls.cells, ls.cells + 3, shape.cells)) {
            r.grid = last->refreshComplete(samples);
            clock.mark("refresh");
        } else {
            r.grid = Grid::completeFromDense(shape, samples, so.blockSize, so.bandVoxels);
            clock.mark("sparsify");
        }
    } else {
        r.grid = Grid::sparseFromDense(shape, samples, so.blockSize, so.bandVoxels);
        clock.mark("sparsify");
    }
}

double meshBakeBytes(const TriangleMesh& mesh, const GridShape& shape, const MeshBakeOptions& o,
                     bool verify, double gridShare) {
    // Bytes per grid vertex of the working arrays: samples (sparse exact: per-block tables, the
    // near owners' samples and the grid, 0.4 measured on a million-triangle rock at 2048 cells);
    // rtsdf adds a coarse grid; the propagation methods hold seed points, triangles and ping-pong
    // or feature arrays. Embree's BVH and the mesh: about 160 bytes a triangle.
    double perVertex = o.method == MeshBakeMethod::Exact
                           ? (o.sampling.kind == GridKind::Dense ? 4 : 0.4)
                       : o.method == MeshBakeMethod::Rtsdf ? 8
                                                           : 40;
    if (verify) perVertex += 8;
    return perVertex * static_cast<double>(shape.vertexCount()) * gridShare +
           160.0 * static_cast<double>(mesh.triangles.size());
}

void checkMeshBake(const TriangleMesh& mesh, const MeshBakeOptions& o, double gridShare) {
    validateMeshBakeOptions(o);
    if (mesh.triangles.empty()) throw InputError("mesh: no (non-degenerate) triangles to bake");
    if (std::string problem = meshRangeProblem(mesh); !problem.empty())
        throw InputError("mesh: " + problem);
    {
        const GridShape shape = o.shape ? *o.shape : gridShapeFor(mesh.bounds(), o.sampling);
        checkMemoryBudget(
            meshBakeBytes(mesh, shape, o, false, gridShare),
            "resolution " + std::to_string(o.sampling.resolution),
            "the bake's grid, working arrays and BVH at " + std::to_string(shape.cells[0]) + "x" +
                std::to_string(shape.cells[1]) + "x" + std::to_string(shape.cells[2]) + " cells",
            "use a lower resolution or a sparse exact bake");
    }
}

MeshBakeResult bakeMesh(const TriangleMesh& mesh, const MeshBakeOptions& o) {
    checkMeshBake(mesh, o);
    // Every stage, grid finishing included, on exactly the requested threads.
    ThreadArena arena(o.sampling.threads);
    MeshBakeResult r;
    arena.execute([&] { r = bakeInArena(mesh, o); });
    return r;
}

}  // namespace sdft
