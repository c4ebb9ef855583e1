#include <cub/device/device_radix_sort.cuh>

#include "cuda_launch.cuh"
#include "gpu_lbvh.cuh"

namespace sdft::cuda {

namespace {

constexpr int kThreads = 256;

__global__ void keyKernel(const Vec3* positions, const uint32_t* triangles, int n, LbvhFrame frame,
                          uint64_t* keys) {
    const int t = blockIdx.x * blockDim.x + threadIdx.x;
    if (t >= n) return;
    const uint32_t* tri = triangles + 3 * static_cast<size_t>(t);
    keys[t] = lbvhKey(positions[tri[0]], positions[tri[1]], positions[tri[2]], frame.lo,
                      frame.invExtent, static_cast<uint32_t>(t));
}

__global__ void gatherKernel(const uint64_t* keys, const Vec3* positions, const uint32_t* triangles,
                             int n, LbvhTriangle* out) {
    const int i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const uint32_t id = static_cast<uint32_t>(keys[i] & 0xFFFFFFFFu);
    const uint32_t* tri = triangles + 3 * static_cast<size_t>(id);
    out[i] = {positions[tri[0]], positions[tri[1]], positions[tri[2]], id};
}

__global__ void nodeKernel(const uint64_t* keys, int n, LbvhNode* nodes, int32_t* parentOfNode,
                           int32_t* parentOfLeaf) {
    const int i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n - 1) return;
    const LbvhChildren c = lbvhInternalNode(keys, n, i);
    nodes[i].left = c.left;
    nodes[i].right = c.right;
    if (c.left < 0)
        parentOfLeaf[~c.left] = i;
    else
        parentOfNode[c.left] = i;
    if (c.right < 0)
        parentOfLeaf[~c.right] = i;
    else
        parentOfNode[c.right] = i;
}

// A child's box read past the L1 cache: another block may have written it.
__device__ void childBox(const LbvhNode* nodes, const LbvhTriangle* tris, int32_t child, Vec3& lo,
                         Vec3& hi) {
    if (child < 0) {
        const LbvhTriangle& t = tris[~child];
        lo = min(t.a, min(t.b, t.c));
        hi = max(t.a, max(t.b, t.c));
        return;
    }
    const LbvhNode* n = nodes + child;
    lo = Vec3(__ldcg(&n->lo.x), __ldcg(&n->lo.y), __ldcg(&n->lo.z));
    hi = Vec3(__ldcg(&n->hi.x), __ldcg(&n->hi.y), __ldcg(&n->hi.z));
}

// From each leaf up: the second thread to reach a node fills its box (Karras §4).
__global__ void boxKernel(const LbvhTriangle* tris, int n, LbvhNode* nodes,
                          const int32_t* parentOfNode, const int32_t* parentOfLeaf, int* visits) {
    const int leaf = blockIdx.x * blockDim.x + threadIdx.x;
    if (leaf >= n) return;
    int32_t node = parentOfLeaf[leaf];
    while (node >= 0) {
        __threadfence();  // this thread's box (if any) visible before the count
        if (atomicAdd(visits + node, 1) == 0) return;
        __threadfence();
        Vec3 llo, lhi, rlo, rhi;
        childBox(nodes, tris, nodes[node].left, llo, lhi);
        childBox(nodes, tris, nodes[node].right, rlo, rhi);
        nodes[node].lo = min(llo, rlo);
        nodes[node].hi = max(lhi, rhi);
        node = parentOfNode[node];
    }
}

}  // namespace

DeviceLbvh::DeviceLbvh(const Vec3* positions, const uint32_t* triangles, int n, LbvhFrame frame)
    : m_count(n), m_nodes(n > 1 ? n - 1 : 0), m_triangles(n) {
    if (n == 0) return;
    EventTimer timer;
    DeviceArray<uint64_t> keys(n), sorted(n);
    size_t tempBytes = 0;
    SDFT_CUDA_CHECK(
        cub::DeviceRadixSort::SortKeys(nullptr, tempBytes, keys.get(), sorted.get(), n, 0, 62));
    DeviceArray<unsigned char> temp(tempBytes);
    SDFT_CUDA_CHECK(cudaEventRecord(timer.start));
    cuda::launch("keyKernel", n, kThreads, keyKernel, positions, triangles, n, frame, keys.get());
    SDFT_CUDA_CHECK(
        cub::DeviceRadixSort::SortKeys(temp.get(), tempBytes, keys.get(), sorted.get(), n, 0, 62));
    cuda::launch("gatherKernel", n, kThreads, gatherKernel, sorted.get(), positions, triangles, n,
                 m_triangles.get());
    if (n > 1) {
        m_parentOfNode = DeviceArray<int32_t>(n - 1);
        m_parentOfLeaf = DeviceArray<int32_t>(n);
        DeviceArray<int> visits(n - 1);
        SDFT_CUDA_CHECK(cudaMemset(m_parentOfNode.get(), 0xFF, (n - 1) * sizeof(int32_t)));
        SDFT_CUDA_CHECK(cudaMemset(visits.get(), 0, (n - 1) * sizeof(int)));
        cuda::launch("nodeKernel", n - 1, kThreads, nodeKernel, sorted.get(), n, m_nodes.get(),
                     m_parentOfNode.get(), m_parentOfLeaf.get());
        cuda::launch("boxKernel", n, kThreads, boxKernel, m_triangles.get(), n, m_nodes.get(),
                     m_parentOfNode.get(), m_parentOfLeaf.get(), visits.get());
        SDFT_CUDA_CHECK(cudaEventRecord(timer.stop));
        m_buildMs = timer.elapsedMs();  // waits for the kernels before the arrays go
        return;
    }
    SDFT_CUDA_CHECK(cudaEventRecord(timer.stop));
    m_buildMs = timer.elapsedMs();
}

}  // namespace sdft::cuda
