#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

#include "cuda_launch.cuh"
#include "device_buffer.h"
#include "sdftrace/core/error.h"
#include "sdftrace/field/complete_block.h"
#include "sdftrace/field/complete_skip.h"
#include "sdftrace/gpu/gpu_complete_grid.h"
#include "sdftrace/gpu/gpu_device.h"

namespace sdft {

namespace {

constexpr int kThreads = 256;

unsigned blocksFor(size_t n) { return static_cast<unsigned>((n + kThreads - 1) / kThreads); }

template <int B>
__global__ void refreshBlocksKernel(CompleteRefreshView v) {
    const int64_t d = static_cast<int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (d >= v.surfaceBlocks) return;
    refreshCompleteBlock<B>(v, static_cast<int32_t>(d));
}

// The largest block bound, as bits: non-negative floats order as their bits do.
__global__ void maxWorstKernel(const float* worst, int32_t n, unsigned* out) {
    float m = 0;
    for (int64_t i = static_cast<int64_t>(blockIdx.x) * blockDim.x + threadIdx.x; i < n;
         i += static_cast<int64_t>(gridDim.x) * blockDim.x)
        m = maxOfFloats(m, worst[i]);
    atomicMax(out, __float_as_uint(m));
}

// This thread's entry i of an nx x ny x nz array (x fastest) and its coordinates; false past
// its end.
__device__ inline bool arrayThread(int nx, int ny, int nz, size_t& i, int& x, int& y, int& z) {
    i = static_cast<size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= static_cast<size_t>(nx) * ny * nz) return false;
    x = static_cast<int>(i % nx);
    y = static_cast<int>(i / nx % ny);
    z = static_cast<int>(i / nx / ny);
    return true;
}

// The kernels of the skip distances: complete_skip.h's functions, one padded block or tile each.
__global__ void blockSourcesKernel(GridView g, int px, int py, int pz, uint8_t* d) {
    size_t i;
    int x, y, z;
    if (arrayThread(px, py, pz, i, x, y, z)) d[i] = blockSkipSource(g, x, y, z);
}

template <class T>
__global__ void dilateKernel(const T* in, T* out, int nx, int ny, int nz) {
    size_t i;
    int x, y, z;
    if (arrayThread(nx, ny, nz, i, x, y, z)) out[i] = chebyshevStep(in, nx, ny, nz, x, y, z);
}

__global__ void writeBlockSkipKernel(GridView g, int px, int py, int pz, const uint8_t* d,
                                     uint8_t* blockSkip) {
    size_t i;
    int x, y, z;
    if (arrayThread(px, py, pz, i, x, y, z)) blockSkip[completePaddedSlot(g, x, y, z)] = d[i];
}

__global__ void tileSourcesKernel(GridView g, int px, int py, const uint8_t* d, uint16_t* t) {
    size_t i;
    int x, y, z;
    if (arrayThread(g.tiles[0], g.tiles[1], g.tiles[2], i, x, y, z))
        t[i] = tileSkipSource(d, px, py, x, y, z);
}

__global__ void writeTileSkipKernel(const uint16_t* t, size_t n, uint8_t* tileSkip) {
    const size_t i = static_cast<size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i < n) tileSkip[i] = tileSkipEntry(t[i]);
}

double since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

struct GpuCompleteGrid::Impl {
    GridShape shape;
    int B = 4;
    float band = 0, background = 0;
    int32_t surface = 0;
    int padded[3] = {0, 0, 0};
    cuda::DeviceArray<int32_t> tilePage, blockData, blockNeighbors;
    cuda::DeviceArray<uint8_t> flags, blockSkip, tileSkip, blockLipschitz, tileLipschitz;
    cuda::DeviceArray<float> blockSamples, worst, upload;
    cuda::DeviceArray<uint64_t> cellMasks;
    cuda::DeviceArray<uint8_t> distance[2];  // per padded block
    cuda::DeviceArray<uint16_t> tileDistance[2];
    cuda::DeviceArray<unsigned> worstBits;
    GridView view;
};

GpuCompleteGrid::GpuCompleteGrid(const Grid& g) : m_impl(std::make_unique<Impl>()) {
    requireGpu("GPU complete grid");
    if (!g.isComplete())
        throw InputError(
            "GPU complete grid: the grid is not a complete block grid "
            "(Grid::completeFromDense)");
    Impl& m = *m_impl;
    const GridView host = g.view();
    m.shape = g.shape();
    m.B = g.blockSize();
    m.band = g.completeBand();
    m.background = g.background();
    m.surface = static_cast<int32_t>(g.surfaceBlockCount());
    for (int a = 0; a < 3; ++a) m.padded[a] = host.tiles[a] * kTileBlocks;
    for (int32_t page : g.tilePage())
        if (page < kFirstOwnPage)
            throw InputError("GPU complete grid: a tile without a page of its own");
    m.tilePage = cuda::DeviceArray<int32_t>(g.tilePage());
    m.blockData = cuda::DeviceArray<int32_t>(g.blockData());
    m.blockNeighbors = cuda::DeviceArray<int32_t>(g.blockNeighbors());
    m.flags = cuda::DeviceArray<uint8_t>(g.flags());
    m.blockSkip = cuda::DeviceArray<uint8_t>(g.blockSkip());
    m.tileSkip = cuda::DeviceArray<uint8_t>(g.tileSkip());
    m.blockLipschitz = cuda::DeviceArray<uint8_t>(g.blockLipschitz());
    m.tileLipschitz = cuda::DeviceArray<uint8_t>(g.tileLipschitz());
    m.blockSamples = cuda::DeviceArray<float>(g.blockSamples());
    m.cellMasks = cuda::DeviceArray<uint64_t>(g.cellMasks());
    m.worst = cuda::DeviceArray<float>(static_cast<size_t>(m.surface));
    const size_t paddedCount = static_cast<size_t>(m.padded[0]) * m.padded[1] * m.padded[2];
    for (auto& d : m.distance) d = cuda::DeviceArray<uint8_t>(paddedCount);
    for (auto& t : m.tileDistance) t = cuda::DeviceArray<uint16_t>(g.tileSkip().size());
    m.worstBits = cuda::DeviceArray<unsigned>(1);
    GridView& v = m.view;
    v = host;
    v.tilePage = m.tilePage.get();
    v.flags = m.flags.get();
    v.blockData = m.blockData.get();
    v.blockSamples = m.blockSamples.get();
    v.blockNeighbors = m.blockNeighbors.get();
    v.cellMasks = m.cellMasks.get();
    v.blockSkip = m.blockSkip.get();
    v.tileSkip = m.tileSkip.get();
    v.blockLipschitz = m.blockLipschitz.get();
    v.tileLipschitz = m.tileLipschitz.get();
    v.samples = nullptr;
    v.texcoords = nullptr;
    v.texcoordKind = 0;
    v.gapLattice = nullptr;  // complete grids are not clamped to a band
}

GpuCompleteGrid::~GpuCompleteGrid() = default;
GpuCompleteGrid::GpuCompleteGrid(GpuCompleteGrid&&) noexcept = default;
GpuCompleteGrid& GpuCompleteGrid::operator=(GpuCompleteGrid&&) noexcept = default;
const GridView& GpuCompleteGrid::view() const { return m_impl->view; }

void GpuCompleteGrid::refreshFromHost(const std::vector<float>& dense, GpuRefreshTimes* times) {
    SDFT_CHECK(dense.size() == m_impl->shape.vertexCount());
    m_impl->upload.upload(dense);
    refresh(m_impl->upload.get(), times);
}

void GpuCompleteGrid::refresh(const float* dense, GpuRefreshTimes* times) {
    const auto start = std::chrono::steady_clock::now();
    Impl& m = *m_impl;
    CompleteRefreshView r;
    r.shape = m.shape;
    for (int a = 0; a < 3; ++a) r.blocks[a] = m.view.blocks[a];
    r.band = m.band;
    r.dense = dense;
    r.blockNeighbors = m.blockNeighbors.get();
    r.surfaceBlocks = m.surface;
    r.blockSamples = m.blockSamples.get();
    r.cellMasks = m.cellMasks.get();
    r.worst = m.worst.get();
    cuda::EventTimer blocks, skip;
    SDFT_CUDA_CHECK(cudaEventRecord(blocks.start));
    const size_t surface = static_cast<size_t>(m.surface);  // none: nothing to refresh
    if (m.B == 8)
        cuda::launch("refreshBlocksKernel<8>", surface, kThreads, refreshBlocksKernel<8>, r);
    else
        cuda::launch("refreshBlocksKernel<4>", surface, kThreads, refreshBlocksKernel<4>, r);
    SDFT_CUDA_CHECK(cudaEventRecord(blocks.stop));
    SDFT_CUDA_CHECK(cudaEventRecord(skip.start));
    SDFT_CUDA_CHECK(cudaMemset(m.worstBits.get(), 0, sizeof(unsigned)));
    cuda::launchBlocks("maxWorstKernel", std::min<size_t>(1024, blocksFor(surface)), kThreads,
                       maxWorstKernel, m.worst.get(), m.surface, m.worstBits.get());
    // Block skip distances: sources, 8 dilations (exact up to 8, 9 beyond), into the slots.
    const GridView& g = m.view;
    const int px = m.padded[0], py = m.padded[1], pz = m.padded[2];
    const size_t paddedCount = static_cast<size_t>(px) * py * pz;
    cuda::launch("blockSourcesKernel", paddedCount, kThreads, blockSourcesKernel, g, px, py, pz,
                 m.distance[0].get());
    for (int step = 0; step < kTileBlocks; ++step)
        cuda::launch("dilateKernel<uint8_t>", paddedCount, kThreads, dilateKernel<uint8_t>,
                     m.distance[step & 1].get(), m.distance[(step + 1) & 1].get(), px, py, pz);
    // kTileBlocks (even) steps end in distance[0].
    cuda::launch("writeBlockSkipKernel", paddedCount, kThreads, writeBlockSkipKernel, g, px, py, pz,
                 m.distance[0].get(), m.blockSkip.get());
    // Tile skip distances: the tiles holding a source, dilated across the tile grid.
    const size_t tiles = m.tileSkip.size();
    cuda::launch("tileSourcesKernel", tiles, kThreads, tileSourcesKernel, g, px, py,
                 m.distance[0].get(), m.tileDistance[0].get());
    const int steps = std::max(g.tiles[0], std::max(g.tiles[1], g.tiles[2]));
    for (int step = 0; step < steps; ++step)
        cuda::launch("dilateKernel<uint16_t>", tiles, kThreads, dilateKernel<uint16_t>,
                     m.tileDistance[step & 1].get(), m.tileDistance[(step + 1) & 1].get(),
                     g.tiles[0], g.tiles[1], g.tiles[2]);
    cuda::launch("writeTileSkipKernel", tiles, kThreads, writeTileSkipKernel,
                 m.tileDistance[steps & 1].get(), tiles, m.tileSkip.get());
    SDFT_CUDA_CHECK(cudaEventRecord(skip.stop));
    unsigned bits = 0;
    SDFT_CUDA_CHECK(cudaMemcpy(&bits, m.worstBits.get(), sizeof bits, cudaMemcpyDeviceToHost));
    float worst;
    std::memcpy(&worst, &bits, sizeof worst);
    const float lipschitz = std::max(1.0f, std::sqrt(worst) / m.shape.voxelSize);
    // Grid::computeLocalLipschitz gives every block the global bound when even the gentlest need
    // (its floor, background / (B h)) exceeds half of it: always so for RTSDF's grids, whose band
    // (1e6 voxels) puts the floor far above any field's slope. Other bands stay on the host.
    const float floor =
        std::max(1.0f, m.background / (static_cast<float>(m.B) * m.shape.voxelSize));
    if (!(floor > 0.5f * lipschitz))
        throw std::runtime_error(
            "GPU complete grid: its local Lipschitz bounds would differ from the global one "
            "(a band of " +
            std::to_string(m.band / m.shape.voxelSize) +
            " voxels); refresh it on the host (Grid::refreshComplete)");
    SDFT_CUDA_CHECK(cudaMemset(m.blockLipschitz.get(), 0, m.blockLipschitz.size()));
    SDFT_CUDA_CHECK(cudaMemset(m.tileLipschitz.get(), 0, m.tileLipschitz.size()));
    m.view.lipschitz = lipschitz;
    m.view.lipschitzLevel[0] = lipschitz;
    m.view.lipschitzLevel[1] = lipschitz;
    if (times) {
        times->blocksMs += blocks.elapsedMs();
        times->skipMs += skip.elapsedMs();
        times->totalMs += since(start);
    }
}

GpuCompleteGridArrays GpuCompleteGrid::download() const {
    const Impl& m = *m_impl;
    GpuCompleteGridArrays a;
    m.blockSamples.download(a.blockSamples, m.blockSamples.size());
    m.cellMasks.download(a.cellMasks, m.cellMasks.size());
    m.blockSkip.download(a.blockSkip, m.blockSkip.size());
    m.tileSkip.download(a.tileSkip, m.tileSkip.size());
    m.blockLipschitz.download(a.blockLipschitz, m.blockLipschitz.size());
    m.tileLipschitz.download(a.tileLipschitz, m.tileLipschitz.size());
    a.lipschitz = m.view.lipschitz;
    return a;
}

}  // namespace sdft
