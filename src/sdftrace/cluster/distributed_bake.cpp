#include "sdftrace/cluster/distributed_bake.h"

#include <zstd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <mutex>
#include <stdexcept>

#include "sdftrace/bake/surface_seeds.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/exec/progress.h"
#include "sdftrace/field/block_table.h"

namespace sdft {

namespace {

int blockLayers(const GridShape& shape, int B) { return (shape.cells[2] + B - 1) / B; }

// One slab's bake (an empty slab, where ranks outnumber the layers, bakes nothing).
SlabSamples bakeSlab(const TriangleMesh& mesh, const GridShape& shape, const MeshBakeOptions& o,
                     BlockSlab slab, ExactBakeStats& st) {
    if (slab.last <= slab.first) return SlabSamples{slab, {}, {}};
    const SampleOptions& so = o.sampling;
    return bakeExactSlab(mesh, shape, so.blockSize, so.bandVoxels, o.sign, slab, so.threads, &st);
}

// The counters of a slab's bake added to the job's.
void addSlabStats(ExactBakeStats& total, const ExactBakeStats& st) {
    total.distanceQueries += st.distanceQueries;
    total.signEvaluations += st.signEvaluations;
    total.filmSums += st.filmSums;
    total.surfaceBlocks += st.surfaceBlocks;
}

double phaseSeconds(const ExactBakeStats& st) {
    double seconds = 0;
    for (const BakeStage& b : st.phases) seconds += b.seconds;
    return seconds;
}

// A slab on the wire: its layers, its flags (zstd: runs of one flag compress a thousandfold) and
// its surface blocks' samples.
void packSlab(const SlabSamples& s, const ExactBakeStats& st, ByteWriter& out) {
    out.put(s.slab);
    out.put<uint64_t>(s.flags.size());
    Bytes packed(ZSTD_compressBound(s.flags.size()));
    const size_t n = ZSTD_compress(packed.data(), packed.size(), s.flags.data(), s.flags.size(), 1);
    if (ZSTD_isError(n)) throw std::runtime_error("exact bake: compressing a slab's block flags");
    out.put<uint64_t>(n);
    out.append(packed.data(), n);
    out.put<uint64_t>(s.samples.size());
    out.append(s.samples.data(), s.samples.size() * sizeof(float));
    out.put(st.distanceQueries);
    out.put(st.signEvaluations);
    out.put(st.filmSums);
    out.put(st.surfaceBlocks);
    out.put(phaseSeconds(st));
    out.put(peakResidentMiB());  // this rank's peak so far
}

SlabSamples unpackSlab(ByteReader& in, ExactBakeStats& st, double& seconds, double& peakMiB) {
    SlabSamples s;
    s.slab = in.get<BlockSlab>();
    s.flags.resize(in.get<uint64_t>());
    const auto n = in.get<uint64_t>();
    const size_t got = ZSTD_decompress(s.flags.data(), s.flags.size(), in.take(n), n);
    if (ZSTD_isError(got) || got != s.flags.size())
        throw std::runtime_error("exact bake: a slab's block flags do not decompress");
    s.samples.resize(in.get<uint64_t>());
    in.read(s.samples.data(), s.samples.size() * sizeof(float));
    st.distanceQueries = in.get<size_t>();
    st.signEvaluations = in.get<size_t>();
    st.filmSums = in.get<size_t>();
    st.surfaceBlocks = in.get<size_t>();
    seconds = in.get<double>();
    peakMiB = in.get<double>();
    return s;
}

GridShape shapeOf(const TriangleMesh& mesh, const MeshBakeOptions& o) {
    return o.shape ? *o.shape : gridShapeFor(mesh.bounds(), o.sampling);
}

class SlabWorker : public RoundWorker {
  public:
    SlabWorker(const TriangleMesh& mesh, const MeshBakeOptions& o, std::vector<BlockSlab> slabs)
        : m_mesh(mesh), m_o(o), m_shape(shapeOf(mesh, o)), m_slabs(std::move(slabs)) {}
    void run(int first, int last, ByteWriter& out) override {
        for (int i = first; i < last; ++i) {
            ExactBakeStats st;
            packSlab(bakeSlab(m_mesh, m_shape, m_o, m_slabs.at(i), st), st, out);
        }
    }

  private:
    const TriangleMesh& m_mesh;
    const MeshBakeOptions& m_o;
    GridShape m_shape;
    std::vector<BlockSlab> m_slabs;
};

}  // namespace

namespace {

// Cost per block layer: the blocks that triangles' bands reach in it (each triangle's footprint,
// the blocks of its grown bounds across x and y: what the slab scatters, measures and keeps the
// samples of), and the layer's own per-block arrays (a sixteenth of that per block).
std::vector<double> layerCosts(const TriangleMesh& mesh, const GridShape& shape, int blockSize,
                               float bandVoxels) {
    const int layers = blockLayers(shape, blockSize);
    std::vector<double> cost(layers, 1.0 + static_cast<double>(shape.cells[0]) * shape.cells[1] /
                                               (16.0 * blockSize * blockSize));
    const float grow = bandVoxels * shape.voxelSize;
    for (const auto& t : mesh.triangles) {
        const VertexRange r = triangleVertexRange(shape, mesh.positions[t[0]], mesh.positions[t[1]],
                                                  mesh.positions[t[2]], grow);
        if (r.empty()) continue;
        const int z0 = std::max(0, r.lo[2] / blockSize - 1);
        const int z1 = std::min(layers - 1, r.hi[2] / blockSize);
        // A triangle's footprint in a layer: the blocks of its bounds in x and y, at most the
        // layer (a large diagonal triangle's bounds hold more blocks than it reaches; its area
        // over its z layers is a fairer share of them).
        const double bx = r.hi[0] / blockSize - r.lo[0] / blockSize + 1;
        const double by = r.hi[1] / blockSize - r.lo[1] / blockSize + 1;
        const double footprint = std::min(bx * by, bx + by + (bx * by) / (z1 - z0 + 1));
        for (int z = z0; z <= z1; ++z) cost[z] += footprint;
    }
    return cost;
}

// Consecutive runs of `cost`'s units into `count` slabs of about equal cost; with `atLeastOne`
// every slab gets a unit (count <= units).
std::vector<BlockSlab> splitCosts(const std::vector<double>& cost, int count, bool atLeastOne) {
    const int units = static_cast<int>(cost.size());
    double total = 0;
    for (double c : cost) total += c;
    std::vector<BlockSlab> slabs;
    int at = 0;
    double sum = 0;
    for (int k = 0; k < count; ++k) {
        const double goal = total * (k + 1) / count;
        const int leave = atLeastOne ? count - k - 1 : 0;  // units the later slabs need
        int end = at;
        while (end < units - leave &&
               (k == count - 1 || (atLeastOne && end == at) || sum + cost[end] * 0.5 <= goal))
            sum += cost[end++];
        slabs.push_back({at, end});
        at = end;
    }
    return slabs;
}

}  // namespace

std::vector<BlockSlab> balancedSlabs(const TriangleMesh& mesh, const GridShape& shape,
                                     int blockSize, float bandVoxels, int count) {
    return splitCosts(layerCosts(mesh, shape, blockSize, bandVoxels), count, false);
}

std::vector<BlockSlab> tileSlabs(const TriangleMesh& mesh, const GridShape& shape, int blockSize,
                                 float bandVoxels, int count) {
    const std::vector<double> layer = layerCosts(mesh, shape, blockSize, bandVoxels);
    const int layers = static_cast<int>(layer.size());
    std::vector<double> tile((layers + kTileBlocks - 1) / kTileBlocks, 0.0);
    for (int z = 0; z < layers; ++z) tile[z / kTileBlocks] += layer[z];
    std::vector<BlockSlab> slabs =
        splitCosts(tile, std::min(count, static_cast<int>(tile.size())), true);
    for (BlockSlab& s : slabs) {
        s.first *= kTileBlocks;
        s.last = std::min(layers, s.last * kTileBlocks);
    }
    return slabs;
}

MeshBakeResult bakeExactAcross(WorkFarm& farm, const TriangleMesh& mesh, const MeshBakeOptions& o) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    const SampleOptions& so = o.sampling;
    const GridShape shape = shapeOf(mesh, o);
    const std::vector<BlockSlab> slabs =
        balancedSlabs(mesh, shape, so.blockSize, so.bandVoxels, farm.ranks());
    std::vector<SlabSamples> done(slabs.size());
    ExactBakeStats total;
    std::vector<BakeStage> rank0Phases;
    double slowest = 0, othersPeak = 0;
    std::mutex mutex;
    ByteWriter context;
    context.put<uint64_t>(slabs.size());
    for (const BlockSlab& s : slabs) context.put(s);
    // Rank 0's stderr is a pipe to mpirun: progress lines (exec/progress.h) unless -q.
    Progress bar("sdftrace bake: slabs", slabs.size(), o.progress);
    RoundPlan round;
    round.context = std::move(context.bytes());
    round.items = static_cast<int>(slabs.size());
    round.local = [&](int first, int last) {
        for (int i = first; i < last; ++i) {
            ExactBakeStats st;
            SlabSamples s = bakeSlab(mesh, shape, o, slabs[i], st);
            std::lock_guard lock(mutex);
            done[i] = std::move(s);
            addSlabStats(total, st);
            slowest = std::max(slowest, phaseSeconds(st));
            if (rank0Phases.empty()) rank0Phases = st.phases;
        }
    };
    round.onResult = [&](int, int first, int last, ByteReader& in) {
        for (int i = first; i < last; ++i) {
            ExactBakeStats st;
            double seconds = 0, peak = 0;
            SlabSamples s = unpackSlab(in, st, seconds, peak);
            std::lock_guard lock(mutex);
            if (s.slab.first != slabs[i].first || s.slab.last != slabs[i].last)
                throw std::runtime_error("exact bake: a rank returned another slab");
            done[i] = std::move(s);
            addSlabStats(total, st);
            slowest = std::max(slowest, seconds);
            othersPeak = std::max(othersPeak, peak);
        }
    };
    round.progress = &bar;
    farm.round(round);
    const auto gathered = Clock::now();
    MeshBakeResult r;
    for (const BakeStage& b : rank0Phases) r.stages.push_back({"rank 0 " + b.name, b.seconds});
    r.stages.push_back({"slabs (slowest rank " + std::to_string(slowest).substr(0, 5) + " s)",
                        std::chrono::duration<double>(gathered - start).count()});
    std::vector<const SlabSamples*> parts;
    for (const SlabSamples& s : done)
        if (s.slab.last > s.slab.first) parts.push_back(&s);
    r.grid = assembleExactSlabs(shape, so.blockSize, so.bandVoxels, parts, so.threads);
    r.stages.push_back(
        {"assemble", std::chrono::duration<double>(Clock::now() - gathered).count()});
    char peak[96];
    std::snprintf(peak, sizeof peak, " (the other ranks' peak memory up to %.0f MiB)", othersPeak);
    r.details = exactBakeDetails(total, o, shape) + ", " + std::to_string(farm.ranks()) +
                " ranks, one slab each" + (othersPeak > 0 ? peak : "");
    return r;
}

std::unique_ptr<RoundWorker> exactSlabWorker(const TriangleMesh& mesh,
                                             const MeshBakeOptions& options, const Bytes& context) {
    ByteReader in(context);
    std::vector<BlockSlab> slabs(in.get<uint64_t>());
    for (BlockSlab& s : slabs) s = in.get<BlockSlab>();
    return std::make_unique<SlabWorker>(mesh, options, std::move(slabs));
}

}  // namespace sdft
