// RTSDF's ray-sampled SDF with a ray mask (Tan et al. 2022, §2.1 and §2.3): a coarse SDF by jump
// flooding at half the resolution decides which vertices are near the surface (|coarse| <= d);
// those cast x rays in uniformly random directions through the BVH (Embree) and keep the minimum
// hit distance, signed by the facing of the hits near the vertex where they agree with all hits'
// (§2.1's vote, after Wright 2015), else by the coarse SDF (rtsdfNegative, rtsdf_vertex.h).
// Vertices beyond d keep the coarse value (§2.3). The minimum over x directions overestimates the
// distance: by about d (2 / x) on a plane at distance d.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/bake/sign_method.h"
#include "sdftrace/field/grid.h"

namespace sdft {

// The fine SDF carried from frame to frame for temporal accumulation (RTSDF §2.5.1, eq. 1):
// f_t = min(alpha f_{t-1} + (1 - alpha) c_t, r_t) where the coarse SDF c_t is within the mask
// distance d (f_{t-1} taken as c_t where none exists; c_t's magnitude bounded from below by its
// cell's corners, rtsdfCoarseDistance), f_t = c_t beyond it (no ghost can survive there). The sign
// follows a moving surface at once: the coarse SDF's beyond one coarse voxel of it, nearer the
// frame's own rays' (rtsdfNegative); no vote is carried over. Empty before the first frame; bound
// to one grid shape (a new shape starts afresh).
struct RtsdfDeviceState;  // gpu/gpu_bake.h
struct RtsdfHistory {
    float alpha = 0.95f;
    GridShape shape;
    std::vector<float> fine;  // |f_{t-1}| per vertex, inf where none was refined
    int frames = 0;           // frames accumulated
    // Where the GPU regenerates the field (bakeMeshGpu), the mesh, its LBVH and f_{t-1} stay on
    // the device between frames: `fine` is then empty and `frames` counts the device's frames.
    std::shared_ptr<RtsdfDeviceState> device;
    // The last frame's grid, a complete block grid (Grid::completeFromDense) whose layout the
    // next frame's samples refresh (finishMeshBake); set by the caller that keeps the grid.
    std::shared_ptr<const Grid> grid;
    // The last frame's values are on the device (the device state's grid), not in `grid`, which
    // keeps its layout and an earlier frame's values (MeshBakeOptions::gpuResident).
    bool gridOnDevice = false;
    // Whether the mesh is watertight (rtsdfNegative, rtsdf_vertex.h), for the triangles whose
    // hash is `topology` (0: none yet): a deforming mesh keeps its triangles from frame to frame.
    uint64_t topology = 0;
    bool closed = false;
};

// Whether `mesh` is watertight (isWatertight), remembered in `history` while its triangles stay.
bool rtsdfMeshClosed(RtsdfHistory* history, const TriangleMesh& mesh);

// Eq. 1's previous frame: kept when `history` holds frames of `shape` on the host, else started
// afresh (the first frame, a grid that changed shape, or an accumulation the GPU kept).
void beginRtsdfFrame(RtsdfHistory& history, const GridShape& shape);

// What the fine rays are cast through: Embree's BVH, or the LBVH (lbvh.h) that the GPU bake
// traverses, to compare with it on the CPU.
enum class RtsdfCaster { Embree, Lbvh };

struct RtsdfOptions {
    int rays = 64;         // x, per refined vertex
    float maskVoxels = 3;  // d, in fine voxels
    uint32_t seed = 1;     // of the per-vertex direction sequences (the bake is deterministic)
    SignMethod coarseSign = SignMethod::WindingNumber;
    RtsdfHistory* history = nullptr;  // temporal accumulation across frames (updated in place)
    RtsdfCaster caster = RtsdfCaster::Embree;
};

struct RtsdfStats {
    size_t refined = 0;  // vertices inside the mask
    size_t rays = 0;
    size_t missed = 0;  // refined vertices none of whose rays hit (kept the coarse value)
    double coarseSeconds = 0, raySeconds = 0;
};

// The dense field `coarse` trilinearly interpolated at the vertices of row (j, k) of `fine`
// (vx of them into `out`): GridView::interpolate at each vertex's position, bit for bit, with the
// row's y and z lookups and cell rows done once. The fine pass reads the coarse field at every
// vertex this way (1.5x faster than per vertex at 257^3 and 513^3; memory-bound: an AVX2 build
// of it measured no faster).
void interpolateDenseRow(const GridView& coarse, const GridShape& fine, int j, int k, float* out);

std::vector<float> bakeRtsdfSamples(const TriangleMesh& mesh, const MeshBvh& bvh,
                                    const GridShape& shape, const RtsdfOptions& options,
                                    int threads = 0, RtsdfStats* stats = nullptr);

}  // namespace sdft
