#include <vector>

#include "cuda_launch.cuh"
#include "gpu_minmax.cuh"
#include "sdftrace/gpu/gpu_device.h"
#include "sdftrace/gpu/gpu_primary.h"

namespace sdft {

namespace cuda {

namespace {

// One thread per block (i fastest). counters[0]: squares splatted, counters[1]: a sphere
// reached the camera plane.
__global__ void splatBlocksKernel(TapeView field, int grid, Camera camera, MinMaxShape shape,
                                  float radius, int nx, int ny, int nz, int* lo, int* hi,
                                  unsigned* counters) {
    const size_t id = static_cast<size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (id >= static_cast<size_t>(nx) * ny * nz) return;
    const int i = static_cast<int>(id % nx), j = static_cast<int>(id / nx % ny);
    const int k = static_cast<int>(id / (static_cast<size_t>(nx) * ny));
    Vec3 c;
    if (!minmax::splattedBlock(field.grids[grid], i, j, k, c)) return;
    const BlockSquare sq = minmax::blockSquare(camera, c, radius, shape);
    if (sq.kind == BlockSquare::Kind::Unseen) return;
    atomicAdd(&counters[0], 1u);
    if (sq.kind == BlockSquare::Kind::Everything) {
        atomicOr(&counters[1], 1u);
        return;
    }
    const int enter = __float_as_int(sq.tEnter), exit = __float_as_int(sq.tExit);
    for (int y = sq.y0; y <= sq.y1; ++y)
        for (int x = sq.x0; x <= sq.x1; ++x) {
            const size_t p = static_cast<size_t>(y) * shape.w + x;
            atomicMin(&lo[p], enter);
            atomicMax(&hi[p], exit);
        }
}

__global__ void fillKernel(float* lo, float* hi, size_t n) {
    const size_t i = static_cast<size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    lo[i] = kInfinity;
    hi[i] = -kInfinity;
}

}  // namespace

void DeviceMinMax::build(const TapeView& field, int grid, const GridView& host,
                         const Camera& camera, int resolution) {
    const MinMaxShape shape = minMaxShape(camera.desc(), resolution);
    const size_t n = static_cast<size_t>(shape.w) * shape.h;
    if (m_min.size() < n) {
        m_min = DeviceArray<float>(n);
        m_max = DeviceArray<float>(n);
    }
    // +inf and -inf: the bits of -inf are a negative int, below every positive distance's.
    cuda::launch("minmax fillKernel", n, 256, fillKernel, m_min.get(), m_max.get(), n);
    SDFT_CUDA_CHECK(cudaMemsetAsync(m_counters.get(), 0, 2 * sizeof(unsigned)));
    DeviceArray<unsigned>& counters = m_counters;
    int nb[3];
    minmax::blockCounts(host, nb);
    const size_t blocks = static_cast<size_t>(nb[0]) * nb[1] * nb[2];
    const int threads = 128;
    cuda::launch("splatBlocksKernel", blocks, threads, splatBlocksKernel, field, grid, camera,
                 shape, minmax::blockRadius(host), nb[0], nb[1], nb[2],
                 reinterpret_cast<int*>(m_min.get()), reinterpret_cast<int*>(m_max.get()),
                 counters.get());
    std::vector<unsigned> c;
    counters.download(c, 2);
    m_squares = c[0];
    m_view = {m_min.get(), m_max.get(), shape, c[1] != 0};
}

}  // namespace cuda

GpuMinMax buildMinMaxGpu(const GpuTape& tape, int grid, const GridView& host, const Camera& camera,
                         int resolution) {
    requireGpu("GPU min/max buffer");
    cuda::EventTimer timer;
    SDFT_CUDA_CHECK(cudaEventRecord(timer.start));
    const cuda::DeviceMinMax mm(tape.view(), grid, host, camera, resolution);
    SDFT_CUDA_CHECK(cudaEventRecord(timer.stop));
    GpuMinMax out;
    out.ms = timer.elapsedMs();
    const MinMaxView v = mm.view();
    out.shape = v.shape;
    out.everything = v.everything;
    out.squares = mm.squares();
    const size_t n = static_cast<size_t>(v.shape.w) * v.shape.h;
    out.min.resize(n);
    out.max.resize(n);
    SDFT_CUDA_CHECK(cudaMemcpy(out.min.data(), v.min, n * sizeof(float), cudaMemcpyDeviceToHost));
    SDFT_CUDA_CHECK(cudaMemcpy(out.max.data(), v.max, n * sizeof(float), cudaMemcpyDeviceToHost));
    return out;
}

}  // namespace sdft
