// Mesh bakes on the GPU (issue 14; RTSDF, Tan et al. 2022, §2.1-2.3): the mesh uploaded once, an
// LBVH built on the device (Karras 2012; bake/lbvh.h), then per bake the conservative
// voxelization into seeds, 3D jump flooding, signs by the hierarchical winding number and, for
// RTSDF, the coarse field's ray mask and the fine rays with the front/back vote, the Lipschitz
// relaxation or eq. 1's accumulation. Every kernel body is a header function the CPU bake runs
// too (jump_flood_step.h, surface_seeds.h, winding_view.h, rtsdf_vertex.h, lbvh.h).
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "sdftrace/bake/jump_flood.h"
#include "sdftrace/bake/lbvh.h"
#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/bake/rtsdf_bake.h"
#include "sdftrace/bake/sign_method.h"
#include "sdftrace/bake/winding_view.h"
#include "sdftrace/gpu/gpu_complete_grid.h"

namespace sdft {

// GPU milliseconds of each pass (CUDA events), and the whole call's wall time with its copies.
struct GpuBakeTimes {
    double seedMs = 0;           // voxelization: seeds and their closest points
    double jfaMs = 0;            // every jump-flooding pass
    std::vector<double> passMs;  // one per pass
    double signMs = 0;           // distances and signs
    double rayMs = 0;            // RTSDF's fine rays (inside the mask)
    double relaxMs = 0;          // RTSDF's Lipschitz relaxation (single bakes)
    double totalMs = 0;          // wall time of the call, uploads and downloads included
    double poseMs = 0;           // GpuMeshBaker::pose (wall): uploads, LBVH, winding tree
    double kernelMs() const { return seedMs + jfaMs + signMs + rayMs + relaxMs; }
};

// Where the winding-number tree of the signs comes from: the CPU bake's median-split tree, built
// on the host and uploaded (the GPU's signs are the CPU's), or the dipoles over the LBVH, built on
// the device (bake/winding_lbvh.h: no host work when a mesh is posed every frame).
enum class GpuWinding { MedianTree, Lbvh };

// The mesh as it stands on the device, in the arrays a GPU renderer's triangle primaries read
// (MeshPrimaryMesh, render/mesh_primary.h): the LBVH, area-weighted unit vertex normals (as the
// host's smoothNormals) and 3 indices per triangle. Valid until the baker's next pose() or end:
// a holder of one compares GpuMeshBaker::poses() with the count it was taken at.
struct GpuMeshSurface {
    LbvhView bvh;
    const Vec3* normals = nullptr;
    const uint32_t* indices = nullptr;
};

class GpuMeshBaker {
  public:
    // Uploads the mesh, builds its LBVH on the device and its winding-number tree. Throws
    // InputError when no GPU can be used, std::runtime_error naming the CUDA call that failed.
    explicit GpuMeshBaker(const TriangleMesh& mesh, GpuWinding winding = GpuWinding::MedianTree);
    ~GpuMeshBaker();
    GpuMeshBaker(GpuMeshBaker&&) noexcept;
    GpuMeshBaker& operator=(GpuMeshBaker&&) noexcept;

    double lbvhBuildMs() const;  // keys, sort, nodes and boxes on the device
    size_t deviceBytes() const;  // the mesh, the LBVH and the winding tree

    // Seeds, jump flooding, distances and signs (winding or beta) at every vertex of `shape`.
    std::vector<float> jumpFlood(const GridShape& shape, JfaVariant variant, SignMethod sign,
                                 float betaVoxels, GpuBakeTimes* times = nullptr) const;
    // RTSDF's fine field (bakeRtsdfSamples on the GPU; options.history accumulates frames, copied
    // to the device and back each call; options.caster is ignored: rays go through the LBVH).
    std::vector<float> rtsdf(const GridShape& shape, const RtsdfOptions& options,
                             RtsdfStats* stats = nullptr, GpuBakeTimes* times = nullptr) const;

    // The mesh at this frame's pose (RTSDF §2.5: deforming and moving meshes regenerated every
    // frame). With the triangles of the mesh before, only the positions are uploaded, and the
    // LBVH and the winding-number tree (of the constructor's kind) are rebuilt; other triangles
    // are uploaded anew. The accumulation of `accumulate` is kept. Wall ms into
    // times->poseMs.
    void pose(const TriangleMesh& mesh, GpuBakeTimes* times = nullptr);
    // RTSDF's per-frame fine field with eq. 1's accumulation (decay `alpha`) kept on the device
    // between calls: rtsdf() with a history that never leaves the GPU (options.history is
    // ignored). With `from`, the accumulation starts from the host's history instead: its f_{t-1}
    // uploaded where it holds frames of `shape`, else afresh (beginRtsdfFrame's rule). Without,
    // it continues the device's, afresh on the first call and where the shape changed.
    std::vector<float> accumulate(const GridShape& shape, const RtsdfOptions& options, float alpha,
                                  const RtsdfHistory* from = nullptr, RtsdfStats* stats = nullptr,
                                  GpuBakeTimes* times = nullptr);
    // accumulate() without the copy back: the frame's field f_t stays on the device
    // (shape.vertexCount() floats, x fastest), valid until the next call or the baker's end, for
    // a device grid's refresh (gpu_complete_grid.h). Wall ms into times->totalMs.
    const float* accumulateOnDevice(const GridShape& shape, const RtsdfOptions& options,
                                    float alpha, const RtsdfHistory* from = nullptr,
                                    RtsdfStats* stats = nullptr, GpuBakeTimes* times = nullptr);
    int accumulatedFrames() const;  // frames in the device's accumulation
    // The posed mesh for a GPU renderer's triangle primaries (RTSDF's hybrid mode: the triangles
    // of the frame the field was regenerated from, with no host LBVH per frame).
    GpuMeshSurface surface() const;
    // Poses so far, the constructor's included: a surface() taken at another count is stale.
    uint64_t poses() const;

    // The pieces alone, for tests: seeds of `shape`, jump flooding of given seeds, first hits.
    SurfaceSeeds seeds(const GridShape& shape) const;
    std::vector<Vec3> jumpFloodPoints(const GridShape& shape, const std::vector<Vec3>& seeds,
                                      JfaVariant variant, GpuBakeTimes* times = nullptr) const;
    std::vector<LbvhHit> firstHits(const std::vector<Ray>& rays, float tnear) const;
    // The winding-number tree the signs use, copied back: its nodes and corners (9 per triangle
    // in tree order), for WindingView.
    std::vector<WindingNode> windingNodes() const;
    std::vector<float> windingCorners() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

// What a mesh regenerated by RTSDF every frame keeps on the GPU between frames
// (RtsdfHistory::device): its baker, with the mesh, the LBVH and the accumulation, and for a GPU
// renderer (MeshBakeOptions::gpuResident) the frame's complete block grid, refreshed there.
struct RtsdfDeviceState {
    GpuMeshBaker baker;
    std::optional<GpuCompleteGrid> grid;
};

// bakeMesh (mesh_bake.h) on the GPU, for the methods it has (jfa and rtsdf); InputError naming
// the flag for the others, a sign method it lacks, or no GPU. An rtsdf bake with a history keeps
// its baker and accumulation on the device in the history (RtsdfHistory::device) and poses the
// mesh there on the next frame. With MeshBakeOptions::gpuResident, the first frame's grid is
// uploaded as the device grid too, and each later frame of the same grid shape refreshes it from
// the field on the device: the result is then onDevice, without a grid, and the history's host
// grid stands in (RtsdfHistory::gridOnDevice).
MeshBakeResult bakeMeshGpu(const TriangleMesh& mesh, const MeshBakeOptions& options);

// Why `options` cannot bake on the GPU, in one sentence; empty when it can.
std::string gpuBakeUnsupported(const MeshBakeOptions& options);

}  // namespace sdft
