#include <chrono>
#include <memory>
#include <vector>

#include "cuda_launch.cuh"
#include "device_buffer.h"
#include "gpu_lbvh.cuh"
#include "sdftrace/bake/closest_point.h"
#include "sdftrace/bake/jump_flood_step.h"
#include "sdftrace/bake/rtsdf_vertex.h"
#include "sdftrace/bake/surface_seeds.h"
#include "sdftrace/bake/winding_lbvh.h"
#include "sdftrace/bake/winding_number.h"
#include "sdftrace/core/error.h"
#include "sdftrace/gpu/gpu_bake.h"
#include "sdftrace/gpu/gpu_device.h"

namespace sdft {

namespace {

constexpr int kThreads = 256;
constexpr unsigned long long kNoCandidate = ~0ull;

__device__ inline void vertexOf(const GridShape& s, size_t idx, int& i, int& j, int& k) {
    const size_t vx = s.vertices(0), vy = s.vertices(1);
    i = static_cast<int>(idx % vx);
    j = static_cast<int>((idx / vx) % vy);
    k = static_cast<int>(idx / (vx * vy));
}

// Voxelization (RTSDF §2.2), one thread per triangle: each vertex within the seed reach of it
// keeps the nearest triangle, ties to the lowest index (the CPU visits triangles in index order
// and keeps the first of equal distances), as one 64-bit key: distance bits above the index.
__global__ void seedScatterKernel(const Vec3* positions, const uint32_t* triangles, int count,
                                  GridShape s, unsigned long long* best) {
    const int t = blockIdx.x * blockDim.x + threadIdx.x;
    if (t >= count) return;
    const uint32_t* tri = triangles + 3 * static_cast<size_t>(t);
    const Vec3 a = positions[tri[0]], b = positions[tri[1]], c = positions[tri[2]];
    const float reach = seedReach(s);
    const VertexRange r = triangleVertexRange(s, a, b, c, s.voxelSize);
    if (r.empty()) return;
    for (int k = r.lo[2]; k <= r.hi[2]; ++k)
        for (int j = r.lo[1]; j <= r.hi[1]; ++j)
            for (int i = r.lo[0]; i <= r.hi[0]; ++i) {
                const Vec3 p = vertexPosition(s, i, j, k);
                const float d = length(p - closestPointOnTriangle(p, a, b, c));
                if (d > reach) continue;
                const unsigned long long key =
                    (static_cast<unsigned long long>(__float_as_uint(d)) << 32) | t;
                atomicMin(best + vertexIndex(s, i, j, k), key);
            }
}

// The winning triangle's closest point at each seed vertex.
__global__ void seedResolveKernel(const unsigned long long* best, const Vec3* positions,
                                  const uint32_t* triangles, GridShape s, size_t n, Vec3* points,
                                  uint32_t* seedTriangle) {
    const size_t idx = static_cast<size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (idx >= n) return;
    const unsigned long long key = best[idx];
    if (key == kNoCandidate) {
        points[idx] = Vec3(kNoSeed);
        if (seedTriangle) seedTriangle[idx] = 0;
        return;
    }
    const uint32_t t = static_cast<uint32_t>(key & 0xFFFFFFFFu);
    const uint32_t* tri = triangles + 3 * static_cast<size_t>(t);
    int i, j, k;
    vertexOf(s, idx, i, j, k);
    points[idx] = closestPointOnTriangle(vertexPosition(s, i, j, k), positions[tri[0]],
                                         positions[tri[1]], positions[tri[2]]);
    if (seedTriangle) seedTriangle[idx] = t;
}

__global__ void jumpFloodKernel(GridShape s, size_t n, const Vec3* in, Vec3* out, int offset) {
    const size_t idx = static_cast<size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (idx >= n) return;
    int i, j, k;
    vertexOf(s, idx, i, j, k);
    out[idx] = jumpFloodVertex(s, in, i, j, k, offset);
}

// distancesToPoints, then the sign: the winding number's (beta > 0) or the beta shell's.
__global__ void signedDistanceKernel(GridShape s, size_t n, const Vec3* points, WindingView w,
                                     double windingBeta, float shell, float* out) {
    const size_t idx = static_cast<size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (idx >= n) return;
    int i, j, k;
    vertexOf(s, idx, i, j, k);
    const Vec3 p = vertexPosition(s, i, j, k), q = points[idx];
    const float d = q.x == kNoSeed ? kNoSeed : length(p - q);
    if (shell > 0) {
        out[idx] = d - shell;
        return;
    }
    out[idx] = windingInside(w, p, windingBeta) ? -d : d;
}

// RTSDF §2.1, §2.3 and §2.5.1 per fine vertex: the coarse value, and inside the mask the rays
// through the LBVH with their vote, single or accumulated (history non-null).
__global__ void rtsdfFineKernel(GridShape s, size_t n, GridView coarse, LbvhView bvh, float mask,
                                float tiny, int rays, uint32_t seed, int frame, float* history,
                                float alpha, bool closed, float* out, unsigned long long* counts) {
    const size_t idx = static_cast<size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    bool refined = false, missed = false;
    if (idx < n) {
        int i, j, k;
        vertexOf(s, idx, i, j, k);
        const Vec3 p = vertexPosition(s, i, j, k);
        const float c = coarse.interpolate(p);
        out[idx] = c;
        if (fabsf(c) > mask) {
            if (history) history[idx] = INFINITY;
        } else {
            refined = true;
            const float cd = rtsdfCoarseDistance(coarse, p, c);
            const RtsdfRays r = castRtsdfRays(LbvhCaster{bvh}, p, rtsdfRayStream(seed, idx, frame),
                                              rays, tiny, rtsdfReach(cd, s.voxelSize));
            missed = r.best == INFINITY;
            out[idx] = history ? rtsdfAccumulate(history[idx], alpha, c, cd, r, s.voxelSize, closed)
                               : rtsdfSingleValue(c, cd, r, s.voxelSize, closed);
        }
    }
    const int blockRefined = __syncthreads_count(refined),
              blockMissed = __syncthreads_count(missed);
    if (threadIdx.x == 0) {
        atomicAdd(counts, static_cast<unsigned long long>(blockRefined));
        atomicAdd(counts + 1, static_cast<unsigned long long>(blockMissed));
    }
}

// One thread per line along `axis` (rtsdf_vertex.h's relaxLine).
__global__ void relaxKernel(float* f, int nx, int ny, int nz, int axis, float h) {
    const int n[3] = {nx, ny, nz};
    const size_t stride[3] = {1, static_cast<size_t>(nx), static_cast<size_t>(nx) * ny};
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    const size_t line = static_cast<size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (line >= static_cast<size_t>(n[a]) * n[b]) return;
    const size_t ja = line % n[a], jb = line / n[a];
    relaxLine(f, ja * stride[a] + jb * stride[b], stride[axis], n[axis], h);
}

__global__ void fillKernel(float* a, size_t n, float value) {
    const size_t i = static_cast<size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i < n) a[i] = value;
}

// Area-weighted vertex normals (the host's smoothNormals, scene/placed_meshes.cpp): each
// triangle adds its doubled area vector to its vertices (atomically, so the sum's order, and its
// last bits, vary), then each vertex's sum is made unit.
__global__ void vertexNormalSumKernel(const Vec3* positions, const uint32_t* triangles, int n,
                                      Vec3* normals) {
    const int j = blockIdx.x * blockDim.x + threadIdx.x;
    if (j >= n) return;
    const uint32_t* t = triangles + 3 * static_cast<size_t>(j);
    const Vec3 a = positions[t[0]];
    const Vec3 area = cross(positions[t[1]] - a, positions[t[2]] - a);
    for (int k = 0; k < 3; ++k) {
        atomicAdd(&normals[t[k]].x, area.x);
        atomicAdd(&normals[t[k]].y, area.y);
        atomicAdd(&normals[t[k]].z, area.z);
    }
}

__global__ void unitNormalKernel(Vec3* normals, size_t n) {
    const size_t i = static_cast<size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i < n) normals[i] = length(normals[i]) > 0 ? normalize(normals[i]) : Vec3(0, 1, 0);
}

// The dipole tree over the LBVH (bake/winding_lbvh.h): its leaves and corners in key order, then
// from each leaf up, through the parents the LBVH's build kept, the second thread to reach a node
// fills it (the LBVH's box pass).
__global__ void windingLeafKernel(const LbvhTriangle* tris, int n, WindingNode* nodes,
                                  float* corners) {
    const int j = blockIdx.x * blockDim.x + threadIdx.x;
    if (j >= n) return;
    nodes[n - 1 + j] = windingLeaf(tris[j], j);
    windingCorners(tris[j], corners + 9 * static_cast<size_t>(j));
}

// A node read past the L1 cache: another block may have written it.
__device__ WindingNode loadWindingNode(const WindingNode* p) {
    static_assert(sizeof(WindingNode) % sizeof(unsigned) == 0);
    WindingNode n;
    const unsigned* from = reinterpret_cast<const unsigned*>(p);
    unsigned* to = reinterpret_cast<unsigned*>(&n);
    for (size_t k = 0; k < sizeof(WindingNode) / sizeof(unsigned); ++k) to[k] = __ldcg(from + k);
    return n;
}

__global__ void windingUpKernel(const LbvhNode* lbvh, int n, const int32_t* parentOfNode,
                                const int32_t* parentOfLeaf, WindingNode* nodes, int* visits) {
    const int leaf = blockIdx.x * blockDim.x + threadIdx.x;
    if (leaf >= n) return;
    int32_t node = parentOfLeaf[leaf];
    while (node >= 0) {
        __threadfence();  // this thread's node (if any) visible before the count
        if (atomicAdd(visits + node, 1) == 0) return;
        __threadfence();
        const int l = windingNodeOfLbvhChild(lbvh[node].left, n),
                  r = windingNodeOfLbvhChild(lbvh[node].right, n);
        nodes[node] = windingInner(loadWindingNode(nodes + l), loadWindingNode(nodes + r), l, r);
        node = parentOfNode[node];
    }
}

__global__ void firstHitKernel(LbvhView bvh, const Ray* rays, size_t n, float tnear, LbvhHit* out) {
    const size_t i = static_cast<size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i < n) out[i] = lbvhFirstHit(bvh, rays[i], tnear);
}

double since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

bool sameShape(const GridShape& a, const GridShape& b) {
    return a.cells[0] == b.cells[0] && a.cells[1] == b.cells[1] && a.cells[2] == b.cells[2] &&
           a.origin.x == b.origin.x && a.origin.y == b.origin.y && a.origin.z == b.origin.z &&
           a.voxelSize == b.voxelSize;
}

std::vector<uint32_t> triangleIndices(const TriangleMesh& mesh) {
    std::vector<uint32_t> indices(3 * mesh.triangles.size());
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
        for (int v = 0; v < 3; ++v) indices[3 * t + v] = mesh.triangles[t][v];
    return indices;
}

}  // namespace

struct GpuMeshBaker::Impl {
    int count = 0;
    GpuWinding windingSource = GpuWinding::MedianTree;
    std::vector<uint32_t> indices;  // the host's copy of `triangles`, for pose()
    bool closed = false;            // the mesh is watertight (rtsdfNegative, rtsdf_vertex.h)
    cuda::DeviceArray<Vec3> positions;
    cuda::DeviceArray<uint32_t> triangles;
    std::unique_ptr<cuda::DeviceLbvh> lbvh;
    uint64_t poses = 0;  // build() calls: the constructor's and each pose()
    cuda::DeviceArray<WindingNode> windingNodes;
    cuda::DeviceArray<float> windingCorners;
    double windingBeta = 3.0;
    // accumulate()'s f_{t-1} (RTSDF eq. 1) on the device, of `accumulatedShape`.
    cuda::DeviceArray<float> accumulation;
    GridShape accumulatedShape;
    int accumulated = 0;
    cuda::DeviceArray<float> field;   // accumulateOnDevice()'s last frame f_t
    cuda::DeviceArray<Vec3> normals;  // surface()'s, of the current pose (none: not made yet)
    bool normalsMade = false;

    // The mesh on the device: positions, triangles (unless `sameTriangles`), the LBVH built
    // there, and the winding-number tree: the median split built on the host and uploaded (the
    // CPU bake's very tree: the GPU's signs are the CPU's), or the dipoles over the LBVH.
    void build(const TriangleMesh& mesh, bool sameTriangles) {
        if (mesh.triangles.size() > static_cast<size_t>(kMaxLbvhTriangles))
            throw InputError("mesh: too many triangles for the GPU bake's LBVH");
        count = static_cast<int>(mesh.triangles.size());
        positions.upload(mesh.positions);
        if (!sameTriangles) {
            indices = triangleIndices(mesh);
            closed = isWatertight(mesh);
            triangles = cuda::DeviceArray<uint32_t>(indices);
        }
        lbvh = std::make_unique<cuda::DeviceLbvh>(positions.get(), triangles.get(), count,
                                                  lbvhFrame(mesh));
        normalsMade = false;
        ++poses;  // the surface's arrays are new: views of the last pose's are stale
        if (windingSource == GpuWinding::Lbvh) {
            windingOverLbvh();
            return;
        }
        const WindingNumber w(mesh);
        const WindingView v = w.view();
        windingBeta = w.beta();
        windingNodes.upload(std::vector<WindingNode>(v.nodes, v.nodes + v.nodeCount));
        windingCorners.upload(std::vector<float>(v.corners, v.corners + 9 * mesh.triangles.size()));
    }

    // bake/winding_lbvh.h's tree on the device (WindingNumber's default beta).
    void windingOverLbvh() {
        const int n = count;
        windingBeta = 3.0;
        if (n == 0) {
            windingNodes = {};
            windingCorners = {};
            return;
        }
        if (windingNodes.size() != 2 * static_cast<size_t>(n) - 1)
            windingNodes = cuda::DeviceArray<WindingNode>(2 * static_cast<size_t>(n) - 1);
        if (windingCorners.size() != 9 * static_cast<size_t>(n))
            windingCorners = cuda::DeviceArray<float>(9 * static_cast<size_t>(n));
        const LbvhView v = lbvh->view();
        cuda::launch("windingLeafKernel", n, kThreads, windingLeafKernel, v.triangles, n,
                     windingNodes.get(), windingCorners.get());
        if (n < 2) return;
        cuda::DeviceArray<int> visits(n - 1);
        SDFT_CUDA_CHECK(cudaMemset(visits.get(), 0, (n - 1) * sizeof(int)));
        cuda::launch("windingUpKernel", n, kThreads, windingUpKernel, v.nodes, n,
                     lbvh->parentOfNode(), lbvh->parentOfLeaf(), windingNodes.get(), visits.get());
        SDFT_CUDA_CHECK(cudaDeviceSynchronize());  // before the counts go
    }

    // The vertex normals of the current pose, made on first use after each pose.
    void makeNormals() {
        if (normalsMade) return;
        const size_t n = positions.size();
        if (normals.size() != n) normals = cuda::DeviceArray<Vec3>(n);
        if (n > 0) {
            SDFT_CUDA_CHECK(cudaMemset(normals.get(), 0, n * sizeof(Vec3)));
            if (count > 0) {
                cuda::launch("vertexNormalSumKernel", count, kThreads, vertexNormalSumKernel,
                             positions.get(), triangles.get(), count, normals.get());
            }
            cuda::launch("unitNormalKernel", n, kThreads, unitNormalKernel, normals.get(), n);
        }
        normalsMade = true;
    }

    WindingView winding() const {
        return {windingNodes.get(), static_cast<int>(windingNodes.size()), windingCorners.get()};
    }

    // Seeds of `s` on the device: closest points (kNoSeed in x where none), and their triangles
    // when asked.
    cuda::DeviceArray<Vec3> seeds(const GridShape& s, cuda::DeviceArray<uint32_t>* seedTriangles,
                                  double* ms) const {
        const size_t n = s.vertexCount();
        cuda::DeviceArray<unsigned long long> best(n);
        cuda::DeviceArray<Vec3> points(n);
        cuda::EventTimer timer;
        SDFT_CUDA_CHECK(cudaEventRecord(timer.start));
        SDFT_CUDA_CHECK(cudaMemset(best.get(), 0xFF, n * sizeof(unsigned long long)));
        cuda::launch("seedScatterKernel", count, kThreads, seedScatterKernel, positions.get(),
                     triangles.get(), count, s, best.get());
        cuda::launch("seedResolveKernel", n, kThreads, seedResolveKernel, best.get(),
                     positions.get(), triangles.get(), s, n, points.get(),
                     seedTriangles ? seedTriangles->get() : nullptr);
        SDFT_CUDA_CHECK(cudaEventRecord(timer.stop));
        const double elapsed = timer.elapsedMs();  // and the kernels done before `best` goes
        if (ms) *ms += elapsed;
        return points;
    }

    // Jump flooding in place (ping-pong with a second array).
    void flood(const GridShape& s, cuda::DeviceArray<Vec3>& points, JfaVariant variant,
               GpuBakeTimes* times) const {
        const size_t n = s.vertexCount();
        cuda::DeviceArray<Vec3> other(n);
        for (int offset : jumpFloodOffsets(s, variant)) {
            cuda::EventTimer timer;
            SDFT_CUDA_CHECK(cudaEventRecord(timer.start));
            cuda::launch("jumpFloodKernel", n, kThreads, jumpFloodKernel, s, n, points.get(),
                         other.get(), offset);
            SDFT_CUDA_CHECK(cudaEventRecord(timer.stop));
            std::swap(points, other);
            const double ms = timer.elapsedMs();
            if (times) {
                times->passMs.push_back(ms);
                times->jfaMs += ms;
            }
        }
    }

    // Seeds, flooding, distances and signs: the signed field at every vertex, on the device.
    cuda::DeviceArray<float> signedField(const GridShape& s, JfaVariant variant, SignMethod sign,
                                         float betaVoxels, GpuBakeTimes* times) const {
        if (sign != SignMethod::WindingNumber && sign != SignMethod::BetaShell)
            throw InputError(std::string("--sign ") + signMethodName(sign) +
                             ": the GPU bake signs by winding number or beta shell");
        const size_t n = s.vertexCount();
        double seedMs = 0;
        cuda::DeviceArray<Vec3> points = seeds(s, nullptr, &seedMs);
        if (times) times->seedMs += seedMs;
        flood(s, points, variant, times);
        cuda::DeviceArray<float> out(n);
        cuda::EventTimer timer;
        SDFT_CUDA_CHECK(cudaEventRecord(timer.start));
        const float shell = sign == SignMethod::BetaShell ? betaVoxels * s.voxelSize : 0.0f;
        cuda::launch("signedDistanceKernel", n, kThreads, signedDistanceKernel, s, n, points.get(),
                     winding(), windingBeta, shell, out.get());
        SDFT_CUDA_CHECK(cudaEventRecord(timer.stop));
        const double ms = timer.elapsedMs();
        if (times) times->signMs += ms;
        return out;
    }

    // RTSDF's fine field of `s` on the device (§2.1, §2.3): the coarse SDF by jump flooding at
    // half the resolution over the same region, then the fine vertices within the mask, single
    // and relaxed (history null) or accumulated into `history` (eq. 1, frame `frame`).
    cuda::DeviceArray<float> fine(const GridShape& s, const RtsdfOptions& o, float* history,
                                  int frame, float alpha, RtsdfStats* stats,
                                  GpuBakeTimes& t) const {
        const double before = t.kernelMs();
        const GridShape coarse = rtsdfCoarseShape(s);
        cuda::DeviceArray<float> coarseField =
            signedField(coarse, JfaVariant::Plain, o.coarseSign, 0.5f, &t);
        GridView cv;
        cv.kind = GridKind::Dense;
        cv.shape = coarse;
        cv.samples = coarseField.get();
        const double coarseMs = t.kernelMs() - before;
        const size_t n = s.vertexCount();
        cuda::DeviceArray<float> out(n);
        cuda::DeviceArray<unsigned long long> counts(2);
        SDFT_CUDA_CHECK(cudaMemset(counts.get(), 0, 2 * sizeof(unsigned long long)));
        cuda::EventTimer rays;
        SDFT_CUDA_CHECK(cudaEventRecord(rays.start));
        cuda::launch("rtsdfFineKernel", n, kThreads, rtsdfFineKernel, s, n, cv, lbvh->view(),
                     o.maskVoxels * s.voxelSize, 1e-4f * s.voxelSize, o.rays, o.seed, frame,
                     history, alpha, closed, out.get(), counts.get());
        SDFT_CUDA_CHECK(cudaEventRecord(rays.stop));
        t.rayMs += rays.elapsedMs();
        // A single bake is relaxed; accumulated frames are not (rtsdf_bake.cpp says why).
        if (!history) {
            cuda::EventTimer relax;
            SDFT_CUDA_CHECK(cudaEventRecord(relax.start));
            const int nv[3] = {s.vertices(0), s.vertices(1), s.vertices(2)};
            for (int axis = 0; axis < 3; ++axis) {
                const size_t lines = static_cast<size_t>(nv[(axis + 1) % 3]) *
                                     static_cast<size_t>(nv[(axis + 2) % 3]);
                cuda::launch("relaxKernel", lines, kThreads, relaxKernel, out.get(), nv[0], nv[1],
                             nv[2], axis, s.voxelSize);
            }
            SDFT_CUDA_CHECK(cudaEventRecord(relax.stop));
            t.relaxMs += relax.elapsedMs();
        }
        std::vector<unsigned long long> c;
        counts.download(c, 2);
        if (stats) {
            stats->refined = c[0];
            stats->rays = c[0] * static_cast<size_t>(o.rays);
            stats->missed = c[1];
            stats->coarseSeconds = coarseMs * 1e-3;
            stats->raySeconds = (t.rayMs + t.relaxMs) * 1e-3;
        }
        return out;
    }
};

GpuMeshBaker::GpuMeshBaker(const TriangleMesh& mesh, GpuWinding winding)
    : m_impl(std::make_unique<Impl>()) {
    requireGpu("GPU bake");
    m_impl->windingSource = winding;
    m_impl->build(mesh, false);
}

GpuMeshBaker::~GpuMeshBaker() = default;
GpuMeshBaker::GpuMeshBaker(GpuMeshBaker&&) noexcept = default;
GpuMeshBaker& GpuMeshBaker::operator=(GpuMeshBaker&&) noexcept = default;

double GpuMeshBaker::lbvhBuildMs() const { return m_impl->lbvh->buildMs(); }

size_t GpuMeshBaker::deviceBytes() const {
    const Impl& m = *m_impl;
    return m.positions.size() * sizeof(Vec3) + m.triangles.size() * sizeof(uint32_t) +
           m.lbvh->bytes() + m.windingNodes.size() * sizeof(WindingNode) +
           m.windingCorners.size() * sizeof(float);
}

std::vector<float> GpuMeshBaker::jumpFlood(const GridShape& s, JfaVariant variant, SignMethod sign,
                                           float betaVoxels, GpuBakeTimes* times) const {
    const auto start = std::chrono::steady_clock::now();
    cuda::DeviceArray<float> field = m_impl->signedField(s, variant, sign, betaVoxels, times);
    std::vector<float> out;
    field.download(out, s.vertexCount());
    if (times) times->totalMs = since(start);
    return out;
}

std::vector<float> GpuMeshBaker::rtsdf(const GridShape& s, const RtsdfOptions& o, RtsdfStats* stats,
                                       GpuBakeTimes* times) const {
    const auto start = std::chrono::steady_clock::now();
    GpuBakeTimes local;
    GpuBakeTimes& t = times ? *times : local;
    RtsdfHistory* h = o.history;
    cuda::DeviceArray<float> history;
    if (h) {
        beginRtsdfFrame(*h, s);
        history = cuda::DeviceArray<float>(h->fine);
    }
    const cuda::DeviceArray<float> out = m_impl->fine(
        s, o, h ? history.get() : nullptr, h ? h->frames : 0, h ? h->alpha : 0.0f, stats, t);
    std::vector<float> result;
    out.download(result, s.vertexCount());
    if (h) {
        history.download(h->fine, s.vertexCount());
        ++h->frames;
    }
    t.totalMs = since(start);
    return result;
}

GpuMeshSurface GpuMeshBaker::surface() const {
    Impl& m = *m_impl;
    m.makeNormals();
    return {m.lbvh->view(), m.normals.get(), m.triangles.get()};
}

uint64_t GpuMeshBaker::poses() const { return m_impl->poses; }

void GpuMeshBaker::pose(const TriangleMesh& mesh, GpuBakeTimes* times) {
    const auto start = std::chrono::steady_clock::now();
    Impl& m = *m_impl;
    const bool sameTriangles =
        3 * mesh.triangles.size() == m.indices.size() && triangleIndices(mesh) == m.indices;
    m.build(mesh, sameTriangles);
    if (times) times->poseMs += since(start);
}

std::vector<float> GpuMeshBaker::accumulate(const GridShape& s, const RtsdfOptions& o, float alpha,
                                            const RtsdfHistory* from, RtsdfStats* stats,
                                            GpuBakeTimes* times) {
    const auto start = std::chrono::steady_clock::now();
    GpuBakeTimes local;
    GpuBakeTimes& t = times ? *times : local;
    accumulateOnDevice(s, o, alpha, from, stats, &t);
    std::vector<float> result;
    m_impl->field.download(result, s.vertexCount());
    t.totalMs = since(start);
    return result;
}

const float* GpuMeshBaker::accumulateOnDevice(const GridShape& s, const RtsdfOptions& o,
                                              float alpha, const RtsdfHistory* from,
                                              RtsdfStats* stats, GpuBakeTimes* times) {
    const auto start = std::chrono::steady_clock::now();
    Impl& m = *m_impl;
    GpuBakeTimes local;
    GpuBakeTimes& t = times ? *times : local;
    const size_t n = s.vertexCount();
    if (from && from->frames > 0 && from->fine.size() == n && sameShape(from->shape, s)) {
        m.accumulation.upload(from->fine);  // the host's f_{t-1}
        m.accumulated = from->frames;
        m.accumulatedShape = s;
    } else if (from || m.accumulated == 0 || !sameShape(m.accumulatedShape, s)) {
        // Eq. 1's f_{t-1} before the first frame: none anywhere (beginRtsdfFrame's infinities).
        if (m.accumulation.size() != n) m.accumulation = cuda::DeviceArray<float>(n);
        cuda::launch("fillKernel", n, kThreads, fillKernel, m.accumulation.get(), n, INFINITY);
        m.accumulatedShape = s;
        m.accumulated = 0;
    }
    m.field = m.fine(s, o, m.accumulation.get(), m.accumulated, alpha, stats, t);
    ++m.accumulated;
    SDFT_CUDA_CHECK(cudaDeviceSynchronize());
    t.totalMs = since(start);
    return m.field.get();
}

int GpuMeshBaker::accumulatedFrames() const { return m_impl->accumulated; }

std::vector<WindingNode> GpuMeshBaker::windingNodes() const {
    std::vector<WindingNode> out;
    m_impl->windingNodes.download(out, m_impl->windingNodes.size());
    return out;
}

std::vector<float> GpuMeshBaker::windingCorners() const {
    std::vector<float> out;
    m_impl->windingCorners.download(out, m_impl->windingCorners.size());
    return out;
}

SurfaceSeeds GpuMeshBaker::seeds(const GridShape& s) const {
    const size_t n = s.vertexCount();
    cuda::DeviceArray<uint32_t> triangles(n);
    cuda::DeviceArray<Vec3> points = m_impl->seeds(s, &triangles, nullptr);
    SurfaceSeeds out;
    points.download(out.point, n);
    triangles.download(out.triangle, n);
    return out;
}

std::vector<Vec3> GpuMeshBaker::jumpFloodPoints(const GridShape& s, const std::vector<Vec3>& seeds,
                                                JfaVariant variant, GpuBakeTimes* times) const {
    cuda::DeviceArray<Vec3> points(seeds);
    m_impl->flood(s, points, variant, times);
    std::vector<Vec3> out;
    points.download(out, seeds.size());
    return out;
}

std::vector<LbvhHit> GpuMeshBaker::firstHits(const std::vector<Ray>& rays, float tnear) const {
    cuda::DeviceArray<Ray> in(rays);
    cuda::DeviceArray<LbvhHit> hits(rays.size());
    cuda::launch("firstHitKernel", rays.size(), kThreads, firstHitKernel, m_impl->lbvh->view(),
                 in.get(), rays.size(), tnear, hits.get());
    std::vector<LbvhHit> out;
    hits.download(out, rays.size());
    return out;
}

}  // namespace sdft
