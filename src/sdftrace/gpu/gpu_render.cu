#include <dlfcn.h>

#include <chrono>
#include <cstdint>
#include <optional>

#include "../core/plugin_dirs.h"
#include "device_buffer.h"
#include "gpu_kernel_table.h"
#include "gpu_minmax.cuh"
#include "sdftrace/core/error.h"
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

// The summary's counters of a frame from the kernel's per-pixel counters `c` and the steps,
// traversal and intersection AOVs.
void addCounters(const std::vector<uint32_t>& c, const std::vector<float>& steps,
                 const std::vector<float>& trav, const std::vector<float>& isect, bool paths,
                 RenderStats& st, uint64_t& triangleHits) {
    for (size_t i = 0; i < steps.size(); ++i) {
        const uint32_t* p = c.data() + kCounters * i;
        st.shadowEvaluations += p[0];
        st.aoEvaluations += p[1];
        st.fallbacks += p[2];
        st.hits += p[3];
        st.secondaryRays += p[4];
        st.secondaryEvaluations += p[5];
        st.selfIntersections += p[6];
        if (paths) {
            st.primaryEvaluations += p[7];  // every sample's
            st.shadowRays += p[8];
            st.normalEvaluations += p[9];
        } else {
            st.primaryEvaluations += static_cast<uint64_t>(steps[i]);
            triangleHits += p[7];
        }
        st.traversalSteps += static_cast<uint64_t>(trav[i]);
        st.intersectionTests += static_cast<uint64_t>(isect[i]);
    }
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
                const GpuMeshSurface s = mesh.device->baker.surface();
                meshViews.push_back(
                    {s.bvh, s.normals, s.indices, mesh.toLocal, mesh.normalToWorld, mesh.bias});
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

void GpuDirectRenderer::rebind(int mesh, const GpuMeshSurface& surface) {
    Impl& m = *m_impl;
    SDFT_CHECK(mesh >= 0 && mesh < static_cast<int>(m.meshViews.size()));
    MeshPrimaryMesh& v = m.meshViews[mesh];
    v.bvh = surface.bvh;
    v.normals = surface.normals;
    v.indices = surface.indices;
    m.meshes.upload(m.meshViews);
}

GpuDirectRenderer::~GpuDirectRenderer() = default;
GpuDirectRenderer::GpuDirectRenderer(GpuDirectRenderer&&) noexcept = default;
GpuDirectRenderer& GpuDirectRenderer::operator=(GpuDirectRenderer&&) noexcept = default;

RenderStats GpuDirectRenderer::render(const FrameView& frame, Film& film) const {
    const Impl& m = *m_impl;
    const auto begin = std::chrono::steady_clock::now();
    const int w = film.width, h = film.height;
    const size_t n = film.pixels();
    DirectPixelView view = m.deviceView(frame, w);
    const WhittedPixelTables noTables;
    WhittedPixelView whitted = whittedPixelView(m.plan, noTables);
    whitted.convex = m.convex.get();
    whitted.convexCount = static_cast<int>(m.convex.size());
    cuda::DeviceArray<float> color(3 * n), depth(n), normal(3 * n), steps(n), error(n), shadow(n),
        ao(n), travSteps(n), isectTests(n);
    cuda::DeviceArray<uint32_t> counters(kCounters * n);
    const DirectOut out{color.get(),      depth.get(),   normal.get(), steps.get(),
                        error.get(),      shadow.get(),  ao.get(),     travSteps.get(),
                        isectTests.get(), counters.get()};
    cuda::EventTimer timer;
    SDFT_CUDA_CHECK(cudaEventRecord(timer.start));
    // A lone grid's primary rays narrowed by Jamriška §6's min/max buffer, built on the device
    // for this frame's camera (timed with the kernels).
    std::optional<cuda::DeviceMinMax> minMax;
    const bool paths = m.plan.settings.pathTracing;  // per-sample primary rays, no DDA
    if (usesMinMax(m.plan) && view.primary.ddaGrid >= 0 && !paths) {
        minMax.emplace(view.primary.field, view.primary.ddaGrid, m.plan.ddaGrid->view(),
                       view.primary.camera, m.plan.settings.minMaxResolution);
        view.primary.minMax = minMax->view();
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
    color.download(film.color, 3 * n);
    if (film.has(Aov::Depth)) depth.download(film.depth, n);
    if (film.has(Aov::Normal)) normal.download(film.normal, 3 * n);
    if (film.has(Aov::Error)) error.download(film.error, n);
    if (film.has(Aov::Shadow)) shadow.download(film.shadow, n);
    if (film.has(Aov::Ao)) ao.download(film.ao, n);
    std::vector<float> stepCounts, trav, isect;  // the summary's counters, and AOVs
    steps.download(stepCounts, n);
    travSteps.download(trav, n);
    isectTests.download(isect, n);
    if (film.has(Aov::Steps)) film.steps = stepCounts;
    if (film.has(Aov::TravSteps)) film.travSteps = trav;
    if (film.has(Aov::IsectTests)) film.isectTests = isect;
    std::vector<uint32_t> c;
    counters.download(c, kCounters * n);
    st.primaryRays = paths ? n * static_cast<uint64_t>(pathView.samplesPerPixel) : n;
    uint64_t triangleHits = 0;
    addCounters(c, stepCounts, trav, isect, paths, st, triangleHits);
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
