#include <dlfcn.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "cuda_launch.cuh"
#include "device_buffer.h"
#include "gpu_kernel_table.h"
#include "gpu_minmax.cuh"
#include "sdftrace/core/error.h"
#include "sdftrace/core/plugin_dirs.h"
#include "sdftrace/gpu/gpu_bake.h"
#include "sdftrace/gpu/gpu_device.h"
#include "sdftrace/gpu/gpu_render.h"
#include "sdftrace/gpu/gpu_tape.h"
#include "sdftrace/render/direct_pixel.h"
#include "sdftrace/render/normal_stencil.h"
#include "sdftrace/render/path_pixel.h"
#include "sdftrace/render/whitted_pixel.h"

namespace sdft {

namespace {

using gpu_render::DirectOut;
using gpu_render::kCounters;
static_assert(kTapeMaxScalarRegs ==
                  gpu_render::kMaterialRegFiles[gpu_render::kMaterialRegFileCount - 1],
              "the largest material register file holds every tape");

// The GPU renderer's kernels from libsdftrace_gpu_kernels.so (core/plugin_dirs.h says where it is
// looked for); a missing or mismatched plugin is one clear error.
const gpu_render::KernelTable& kernelTable() {
    struct Loaded {
        const gpu_render::KernelTable* table = nullptr;
        std::string failure;
    };
    static const Loaded loaded = [] {
        const std::string file = "libsdftrace_gpu_kernels.so";
        std::string tried;
        const std::string path = findPlugin(file, tried);
        if (path.empty())
            return Loaded{nullptr, file + " not found (looked for " + tried +
                                       "; `make build` builds it, SDFT_PLUGIN_DIR names its "
                                       "directory)"};
        void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) return Loaded{nullptr, "cannot load " + path + " (" + dlerror() + ")"};
        auto entry = reinterpret_cast<const gpu_render::KernelTable* (*)()>(
            dlsym(handle, "sdftrace_gpu_kernels"));
        const gpu_render::KernelTable* table = entry ? entry() : nullptr;
        if (!table || table->version != gpu_render::KernelTable::kVersion ||
            table->layout != gpu_render::kernelTableLayout())
            return Loaded{nullptr, path + " is not this build's GPU kernels (rebuild sdftrace)"};
        return Loaded{table, {}};
    }();
    if (!loaded.table) throw InputError("the GPU renderer needs its kernels: " + loaded.failure);
    return *loaded.table;
}

// The sums of a frame's counters: the kernel's kCounters per pixel, then its steps, traversal
// steps and intersection tests (integral floats), reduced on the device so that only these come
// back. Each block sums into shared memory first.
constexpr int kSums = kCounters + 3;

__global__ void sumCountersKernel(const uint32_t* counters, const float* steps, const float* trav,
                                  const float* isect, size_t n, unsigned long long* sums) {
    __shared__ unsigned long long local[kSums];
    if (threadIdx.x < kSums) local[threadIdx.x] = 0;
    __syncthreads();
    const size_t stride = static_cast<size_t>(gridDim.x) * blockDim.x;
    for (size_t i = static_cast<size_t>(blockIdx.x) * blockDim.x + threadIdx.x; i < n;
         i += stride) {
        const uint32_t* p = counters + kCounters * i;
        for (int c = 0; c < kCounters; ++c)
            if (p[c]) atomicAdd(&local[c], static_cast<unsigned long long>(p[c]));
        atomicAdd(&local[kCounters], static_cast<unsigned long long>(steps[i]));
        atomicAdd(&local[kCounters + 1], static_cast<unsigned long long>(trav[i]));
        atomicAdd(&local[kCounters + 2], static_cast<unsigned long long>(isect[i]));
    }
    __syncthreads();
    if (threadIdx.x < kSums && local[threadIdx.x])
        atomicAdd(&sums[threadIdx.x], local[threadIdx.x]);
}

// The summary's counters of a frame from the sums of sumCountersKernel.
void addCounters(const unsigned long long* sums, bool paths, RenderStats& st,
                 uint64_t& triangleHits) {
    st.shadowEvaluations += sums[0];
    st.aoEvaluations += sums[1];
    st.fallbacks += sums[2];
    st.hits += sums[3];
    st.secondaryRays += sums[4];
    st.secondaryEvaluations += sums[5];
    st.selfIntersections += sums[6];
    if (paths) {
        st.primaryEvaluations += sums[7];  // every sample's
        st.shadowRays += sums[8];
        st.normalEvaluations += sums[9];
    } else {
        st.primaryEvaluations += sums[kCounters];
        triangleHits += sums[7];
    }
    st.traversalSteps += sums[kCounters + 1];
    st.intersectionTests += sums[kCounters + 2];
}

// A frame's device outputs and its host staging, allocated for the largest film seen and kept:
// a renderer's frames (and, through the pool, the next renderer's: an animation makes one per
// frame) allocate nothing once the film has been this size.
struct FrameBuffers {
    size_t capacity = 0;  // pixels
    cuda::DeviceArray<float> color, depth, normal, steps, error, shadow, ao, trav, isect;
    cuda::DeviceArray<uint32_t> counters;
    cuda::DeviceArray<unsigned long long> sums{kSums};
    cuda::PinnedArray<float> staging;  // the AOVs asked for, one after the other
    cuda::PinnedArray<unsigned long long> sumsHost;
    cuda::EventTimer timer;
    cuda::DeviceMinMax minMax;  // Jamriška §6's buffer of a lone grid's frames

    void ensure(size_t n) {
        if (n <= capacity) return;
        color = cuda::DeviceArray<float>(3 * n);
        normal = cuda::DeviceArray<float>(3 * n);
        for (cuda::DeviceArray<float>* a : {&depth, &steps, &error, &shadow, &ao, &trav, &isect})
            *a = cuda::DeviceArray<float>(n);
        counters = cuda::DeviceArray<uint32_t>(kCounters * n);
        capacity = n;
    }

    DirectOut out() const {
        return {color.get(),  depth.get(), normal.get(), steps.get(), error.get(),
                shadow.get(), ao.get(),    trav.get(),   isect.get(), counters.get()};
    }

    // The device array the kernels write `aov` into (every AOV but motion).
    const float* output(Aov aov) const {
        const DirectOut o = out();
        switch (aov) {
            case Aov::Color:
                return o.color;
            case Aov::Depth:
                return o.depth;
            case Aov::Normal:
                return o.normal;
            case Aov::Steps:
                return o.steps;
            case Aov::Error:
                return o.error;
            case Aov::TravSteps:
                return o.travSteps;
            case Aov::IsectTests:
                return o.isectTests;
            case Aov::Shadow:
                return o.shadow;
            case Aov::Ao:
                return o.ao;
            case Aov::Motion:
                break;
        }
        return nullptr;
    }

    // After a frame of n pixels: its counters summed on the device into sumsHost, and the colour
    // and the AOVs `film` keeps copied into pinned memory asynchronously, then into the film once.
    // Returns the bytes that crossed to the host.
    size_t download(Film& film, size_t n) {
        SDFT_CUDA_CHECK(cudaMemsetAsync(sums.get(), 0, kSums * sizeof(unsigned long long)));
        cuda::launchBlocks("sumCountersKernel", std::min<size_t>(1024, (n + 255) / 256), 256,
                           sumCountersKernel, counters.get(), steps.get(), trav.get(), isect.get(),
                           n, sums.get());
        std::vector<Aov> copied;
        size_t floats = 0;
        for (int a = 0; a < static_cast<int>(Aov::Motion); ++a) {
            const Aov aov = static_cast<Aov>(a);
            if (aov != Aov::Color && !film.has(aov)) continue;
            copied.push_back(aov);
            floats += static_cast<size_t>(aovChannels(aov)) * n;
        }
        staging.reserve(floats);
        sumsHost.reserve(kSums);
        size_t offset = 0;
        for (Aov aov : copied) {
            const size_t count = static_cast<size_t>(aovChannels(aov)) * n;
            SDFT_CUDA_CHECK(cudaMemcpyAsync(staging.get() + offset, output(aov),
                                            count * sizeof(float), cudaMemcpyDeviceToHost));
            offset += count;
        }
        SDFT_CUDA_CHECK(cudaMemcpyAsync(sumsHost.get(), sums.get(),
                                        kSums * sizeof(unsigned long long),
                                        cudaMemcpyDeviceToHost));
        SDFT_CUDA_CHECK(cudaStreamSynchronize(nullptr));
        offset = 0;
        for (Aov aov : copied) {
            const size_t count = static_cast<size_t>(aovChannels(aov)) * n;
            film.channel(aov).assign(staging.get() + offset, staging.get() + offset + count);
            offset += count;
        }
        return floats * sizeof(float) + kSums * sizeof(unsigned long long);
    }
};

// A mesh view's arrays: those of a baker's posed mesh.
void setSurface(MeshPrimaryMesh& v, const GpuMeshSurface& s) {
    v.bvh = s.bvh;
    v.normals = s.normals;
    v.indices = s.indices;
}

// Frame buffers outlive their renderer in this pool and go to the next one.
std::shared_ptr<FrameBuffers> takeFrameBuffers() {
    static std::mutex mutex;
    static std::vector<std::unique_ptr<FrameBuffers>> pool;
    std::unique_ptr<FrameBuffers> b;
    {
        std::lock_guard<std::mutex> lock(mutex);
        if (!pool.empty()) {
            b = std::move(pool.back());
            pool.pop_back();
        }
    }
    if (!b) b = std::make_unique<FrameBuffers>();
    return std::shared_ptr<FrameBuffers>(b.release(), [](FrameBuffers* f) {
        std::lock_guard<std::mutex> lock(mutex);
        pool.emplace_back(f);
    });
}

}  // namespace

struct GpuDirectRenderer::Impl {
    const RenderPlan& plan;
    GpuTape tape;
    DirectPixelTables tables;
    cuda::DeviceArray<Light> lights;
    cuda::DeviceArray<PixelMaterial> materials;
    // Colour textures and their images' pixels on the device, and the images' views of them.
    cuda::DeviceArray<TextureParams> textures;
    std::vector<cuda::DeviceArray<float>> pixels;
    cuda::DeviceArray<ImageView> images;
    // Triangle primaries (RTSDF's hybrid mode): the field without the meshes, and each mesh's
    // LBVH, normals and indices with the views of them.
    std::optional<GpuTape> primaryTape;
    std::vector<cuda::DeviceArray<LbvhNode>> meshNodes;
    std::vector<cuda::DeviceArray<LbvhTriangle>> meshTriangles;
    std::vector<cuda::DeviceArray<Vec3>> meshNormals;
    std::vector<cuda::DeviceArray<uint32_t>> meshIndices;
    std::vector<MeshPrimaryMesh> meshViews;  // the host's copy of `meshes`
    cuda::DeviceArray<MeshPrimaryMesh> meshes;
    // The meshes posed on the device (RTSDF's per-frame meshes): their owner, kept alive here,
    // and the baker's pose count their views were taken at. A later pose replaces the baker's
    // arrays, so render() takes the views anew first (freshMeshes).
    struct PosedMesh {
        size_t index;  // in meshViews
        std::shared_ptr<RtsdfDeviceState> owner;
        uint64_t poses;
    };
    std::vector<PosedMesh> posed;
    // The frames' outputs on the device and their host staging, kept between frames.
    std::shared_ptr<FrameBuffers> frames = takeFrameBuffers();

    // The posed meshes' views as their bakers hold them now (uploaded where a pose changed them).
    void freshMeshes() {
        bool changed = false;
        for (PosedMesh& p : posed) {
            const uint64_t now = p.owner->baker.poses();
            if (now == p.poses) continue;
            setSurface(meshViews[p.index], p.owner->baker.surface());
            p.poses = now;
            changed = true;
        }
        if (changed) meshes.upload(meshViews);
    }
    // Whitted rays: the convex objects' tapes (Keinert §3.5) on the device, and their views.
    bool whitted;
    std::vector<GpuTape> convexTapes;
    cuda::DeviceArray<ConvexView> convex;

    Impl(const RenderPlan& p, const std::vector<GpuGridBinding>& bound)
        : plan(p),
          tape(p.tape, bound),
          tables(directPixelTables(p)),
          lights(tables.lights),
          materials(tables.materials),
          textures(tables.textures),
          whitted(planHasWhitted(p)) {
        std::vector<ImageView> imageViews;
        for (const TextureImage& image : p.images) {
            pixels.emplace_back(image.rgb);
            imageViews.push_back({pixels.back().get(), image.width, image.height});
        }
        images = cuda::DeviceArray<ImageView>(imageViews);
        if (p.primaryField) primaryTape.emplace(*p.primaryField, bound);
        for (const MeshPrimaryTables::Mesh& mesh : tables.meshes.meshes) {
            if (mesh.device) {  // posed on the device with its field: the baker's arrays
                posed.push_back({meshViews.size(), mesh.device, mesh.device->baker.poses()});
                MeshPrimaryMesh v{{},       nullptr, nullptr, mesh.toLocal, mesh.normalToWorld,
                                  mesh.bias};
                setSurface(v, mesh.device->baker.surface());
                meshViews.push_back(v);
                continue;
            }
            meshNodes.emplace_back(mesh.nodes);
            meshTriangles.emplace_back(mesh.triangles);
            meshNormals.emplace_back(mesh.normals);
            meshIndices.emplace_back(mesh.indices);
            meshViews.push_back({{meshNodes.back().get(), meshTriangles.back().get(),
                                  static_cast<int>(mesh.triangles.size())},
                                 meshNormals.back().get(),
                                 meshIndices.back().get(),
                                 mesh.toLocal,
                                 mesh.normalToWorld,
                                 mesh.bias});
        }
        meshes = cuda::DeviceArray<MeshPrimaryMesh>(meshViews);
        if (!whitted) return;
        std::vector<ConvexView> views;
        for (const ConvexObject& c : p.convexObjects) {
            convexTapes.emplace_back(c.tape, bound);
            views.push_back({convexTapes.back().view(), c.bounds});
        }
        convex = cuda::DeviceArray<ConvexView>(views);
    }

    // The plan's view for a frame `width` pixels wide, its arrays the device copies.
    DirectPixelView deviceView(const FrameView& frame, int width) const {
        DirectPixelView view = directPixelView(plan, frame, tables, width);
        view.primary.field = tape.view();
        view.primary.primaryField = primaryTape ? primaryTape->view() : view.primary.field;
        view.primary.meshes = {meshes.get(), static_cast<int>(meshes.size())};
        view.lights = lights.get();
        view.materials = materials.get();
        view.textures = textures.get();
        view.images = {images.get(), static_cast<int>(images.size())};
        return view;
    }
};

GpuDirectRenderer::GpuDirectRenderer(const RenderPlan& plan, const std::string& what,
                                     const std::vector<GpuGridBinding>& bound) {
    requireGpu(what);
    if (const std::string why = directPixelUnsupported(plan); !why.empty())
        throw InputError(what + ": the GPU does not render " + why +
                         " yet (docs/gpu.md); use --device cpu");
    // The plan's grids whose values are on the device (RTSDF's per-frame grids): their device
    // copies, refreshed there, in place of an upload.
    std::vector<GpuGridBinding> all = bound;
    for (const DeviceResidentGrid& d : plan.deviceGrids) {
        if (!d.state || !d.state->grid)
            throw InputError(what + ": a grid of the plan lives on the GPU without a device copy");
        all.push_back({d.grid, d.state->grid->view()});
    }
    m_impl = std::make_unique<Impl>(plan, all);
}

void GpuDirectRenderer::rebind(const GpuGridBinding& binding) {
    Impl& m = *m_impl;
    m.tape.rebind(binding);
    if (m.primaryTape) m.primaryTape->rebind(binding);
    for (GpuTape& t : m.convexTapes) t.rebind(binding);
}

void GpuDirectRenderer::followMesh(int mesh, std::shared_ptr<RtsdfDeviceState> state) {
    Impl& m = *m_impl;
    SDFT_CHECK(mesh >= 0 && mesh < static_cast<int>(m.meshViews.size()) && state);
    const size_t index = static_cast<size_t>(mesh);
    std::erase_if(m.posed, [&](const Impl::PosedMesh& p) { return p.index == index; });
    // A count no baker has: the next render takes the arrays.
    m.posed.push_back({index, std::move(state), ~uint64_t{0}});
}

GpuDirectRenderer::~GpuDirectRenderer() = default;
GpuDirectRenderer::GpuDirectRenderer(GpuDirectRenderer&&) noexcept = default;
GpuDirectRenderer& GpuDirectRenderer::operator=(GpuDirectRenderer&&) noexcept = default;

RenderStats GpuDirectRenderer::render(const FrameView& frame, Film& film) const {
    m_impl->freshMeshes();  // a baker posed since: its new arrays, never the freed ones
    const Impl& m = *m_impl;
    const auto begin = std::chrono::steady_clock::now();
    const int w = film.width, h = film.height;
    const size_t n = film.pixels();
    DirectPixelView view = m.deviceView(frame, w);
    const WhittedPixelTables noTables;
    WhittedPixelView whitted = whittedPixelView(m.plan, noTables);
    whitted.convex = m.convex.get();
    whitted.convexCount = static_cast<int>(m.convex.size());
    FrameBuffers& f = *m.frames;
    f.ensure(n);
    const DirectOut out = f.out();
    const cuda::EventTimer& timer = f.timer;
    SDFT_CUDA_CHECK(cudaEventRecord(timer.start));
    // A lone grid's primary rays narrowed by Jamriška §6's min/max buffer, built on the device
    // for this frame's camera (timed with the kernels).
    const bool paths = m.plan.settings.pathTracing;  // per-sample primary rays, no DDA
    if (usesMinMax(m.plan) && view.primary.ddaGrid >= 0 && !paths) {
        f.minMax.build(view.primary.field, view.primary.ddaGrid, m.plan.ddaGrid->view(),
                       view.primary.camera, m.plan.settings.minMaxResolution);
        view.primary.minMax = f.minMax.view();
    }
    // The material register file: none read with a uniform material, else the smallest that
    // holds the tape's scalar registers.
    const int regs = view.uniformMaterial >= 0                ? 1
                     : view.primary.field.numScalarRegs <= 8  ? 8
                     : view.primary.field.numScalarRegs <= 16 ? 16
                     : view.primary.field.numScalarRegs <= 32 ? 32
                                                              : kTapeMaxScalarRegs;
    PathPixelView pathView;
    if (paths) {
        pathView = pathPixelView(m.plan, frame, m.tables);
        pathView.direct = view;
    }
    // The kernels come from their plugin (gpu_kernel_table.h), loaded on the first render.
    const gpu_render::KernelTable& k = kernelTable();
    const int r = gpu_render::materialRegFileIndex(regs);
    if (paths)
        k.path[r](pathView, w, h, out);
    else
        k.direct[r][m.whitted ? 1 : 0](view, whitted, w, h, out);
    SDFT_CUDA_CHECK(cudaEventRecord(timer.stop));
    RenderStats st;
    st.gpu = true;
    st.gpuKernelMs = timer.elapsedMs();
    st.gpuBytesMoved = f.download(film, n);
    st.primaryRays = paths ? n * static_cast<uint64_t>(pathView.samplesPerPixel) : n;
    uint64_t triangleHits = 0;
    addCounters(f.sumsHost.get(), paths, st, triangleHits);
    st.gridTracer = m.plan.ddaGrid != nullptr && !paths;
    // The DDA's normals read the grid, not the tape, and a triangle's are its own (neither
    // counted, as on the CPU).
    if (!st.gridTracer && !paths)
        st.normalEvaluations =
            (st.hits - triangleHits) * static_cast<uint64_t>(stencilSize(m.plan.settings.normals));
    st.threads = 1;
    st.gpuFrameMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
    st.seconds = st.gpuFrameMs * 1e-3;
    return st;
}

}  // namespace sdft
