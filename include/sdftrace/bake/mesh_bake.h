// Mesh to SDF, every method behind one call: the options a user gives (`sdftrace bake`, scene
// files' mesh objects, `sdftrace render mesh.obj`), the grid, and what each stage took.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "sdftrace/bake/bake_stage.h"
#include "sdftrace/bake/exact_bake.h"
#include "sdftrace/bake/jump_flood.h"
#include "sdftrace/bake/rtsdf_bake.h"
#include "sdftrace/bake/sign_method.h"
#include "sdftrace/field/grid.h"
#include "sdftrace/field/sample_grid.h"

namespace sdft {

enum class MeshBakeMethod {
    Exact,         // closest points through Embree (exact_bake.h); the ground truth
    JumpFlood,     // RTSDF §2.2 (jump_flood.h)
    Danielsson,    // Liktor §3.2 (danielsson.h)
    SeparableEdt,  // exact EDT of the voxelized surface (separable_edt.h)
    Rtsdf,         // RTSDF §2.1 + §2.3 (rtsdf_bake.h)
};

struct MeshBakeOptions {
    MeshBakeMethod method = MeshBakeMethod::Exact;
    SampleOptions sampling;  // resolution, dense or sparse, block, band, padding, threads
    SignMethod sign = SignMethod::WindingNumber;
    ClosestPoints closest = ClosestPoints::Transform;  // exact, dense
    JfaVariant jfaVariant = JfaVariant::Plain;
    float betaVoxels = 0.5f;  // SignMethod::BetaShell
    RtsdfOptions rtsdf;
    bool progress = false;  // percentages on stderr for the long stages
    // The grid's region and voxel (default: from the mesh's bounds and `sampling`): frames that
    // accumulate into one grid keep its shape.
    std::optional<GridShape> shape;
    // An rtsdf frame baked on the GPU for a GPU renderer (render --device cuda): from its second
    // frame on, the field stays on the device and refreshes the history's device grid
    // (bakeMeshGpu, gpu/gpu_bake.h); the result then holds no grid (onDevice).
    bool gpuResident = false;
};

struct MeshBakeResult {
    // Empty when `onDevice`: the frame's values are in the history's device grid, and the
    // history's host grid (RtsdfHistory::grid) stands in for it.
    Grid grid;
    bool onDevice = false;
    std::vector<BakeStage> stages;
    std::string details;  // method-specific counts for the summary line ("" if none)
};

// Throws InputError when the sign method does not apply to the method (exact and rtsdf take
// winding or parity; the propagation methods also flood and beta). bakeMesh checks it first.
void validateMeshBakeOptions(const MeshBakeOptions& options);

// Bytes a bake of `mesh` at `shape` needs at its peak (the grid, the method's working arrays,
// the BVH; `verify` adds the exact bake it is measured against), an estimate made before anything
// is allocated. bakeMesh checks it against the memory budget (core/memory_budget.h).
// `gridShare`: the part of the grid this process bakes (a slab of a distributed bake).
double meshBakeBytes(const TriangleMesh& mesh, const GridShape& shape,
                     const MeshBakeOptions& options, bool verify = false, double gridShare = 1);

// What bakeMesh checks before it starts (InputError): the options, a mesh with triangles in a
// finite range, and the memory budget for `gridShare` of the grid.
void checkMeshBake(const TriangleMesh& mesh, const MeshBakeOptions& options, double gridShare = 1);

MeshBakeResult bakeMesh(const TriangleMesh& mesh, const MeshBakeOptions& options);

// A bake's dense samples as the grid `sampling` asks for (a sparse one marks the "sparsify"
// stage), into r.grid: what every method (and the GPU's, gpu_bake.h) ends with. A frame of
// RTSDF's per-frame regeneration (`history` non-null) gets a complete block grid
// (Grid::completeFromDense): the history's last grid refreshed where it has this shape (the
// "refresh" stage), else one built afresh.
void finishMeshBake(const GridShape& shape, std::vector<float> samples,
                    const SampleOptions& sampling, MeshBakeResult& r, StageClock& clock,
                    const RtsdfHistory* history = nullptr);

// The summary of an exact bake's work (MeshBakeResult::details): distances and signs.
std::string exactBakeDetails(const ExactBakeStats& stats, const MeshBakeOptions& options,
                             const GridShape& shape);

const char* meshBakeMethodName(MeshBakeMethod m);
// "exact", "jfa", "danielsson", "edt", "rtsdf"; false if unknown.
bool parseMeshBakeMethod(const std::string& name, MeshBakeMethod& out);
constexpr const char* kMeshBakeMethods = "exact, jfa, danielsson, edt, rtsdf";

}  // namespace sdft
