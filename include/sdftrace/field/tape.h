// The analytic field compiled to a flat opcode tape (libfive's tree -> tape -> evaluator).
// One instruction per node; registers hold points (for domain transforms) or scalars (distances).
// Evaluators: eval() for one point (the scalar path), evalBatch() for a structure-of-arrays batch
// (one pass of the interpreter serves many rays), evalMaterial() for the material blend at a hit.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "sdftrace/field/grid.h"
#include "sdftrace/field/material_blend.h"
#include "sdftrace/field/node.h"
#include "sdftrace/field/tape_instr.h"
#include "sdftrace/field/tape_view.h"
#include "sdftrace/math/ray.h"

namespace sdft {

struct CompileOptions {
    // Skip union operands whose bounding box is no nearer than the running minimum (decision 0002).
    // The value stays a distance bound with the same zero set; off, the tape equals the tree.
    bool boundsCulling = true;
    // Hierarchical pruning (field/tape_prune.h): per cell of a lattice over the scene, a tape
    // without the operands that cannot change the field in the cell. The same values; a switch to
    // measure it against the whole tape.
    bool pruning = true;
};

// Where a fold's operands start (the compiler's record, which pruning reads): for an instruction
// that combines an accumulator with an operand (Union ... SmoothDifference), the first
// instruction of the operand's own (after its CullIfFar guard, if any) and of the fold's first
// operand.
struct FoldOperands {
    uint32_t operand = 0, fold = 0;
};

// The pruned tapes and their cells (TapeCells is their view).
struct PrunedTapes {
    std::vector<Instr> instrs;
    std::vector<uint32_t> spans;     // first instruction and count, per tape
    std::vector<uint32_t> cellTape;  // per cell
    int res[3] = {0, 0, 0};
    Bounds3 box;
    // A tape for the points outside the box (a top-level union of planes and bounded objects:
    // the planes, and the distance to the objects' box, which the box's margin keeps from 0),
    // or -1: those points take the whole tape.
    int32_t outsideTape = -1;
};

// Scratch registers for evalBatch; one per thread, reused across calls.
struct BatchScratch {
    std::vector<float> points;    // numPointRegs * 3 * kBatchWidth
    std::vector<float> scalars;   // numScalarRegs * kBatchWidth
    std::vector<uint8_t> culled;  // numCulls * kBatchWidth: lanes that skipped an operand
    // A chunk's lanes grouped by the pruned tape of their cell.
    std::vector<uint32_t> laneTape, order;
    std::vector<float> gx, gy, gz, gout;
};

class Tape {
  public:
    static constexpr int kBatchWidth = 64;
    // The scalar evaluator's register files (field/tape_view.h).
    static constexpr int kMaxScalarRegs = kTapeMaxScalarRegs;
    static constexpr int kMaxPointRegs = kTapeMaxPointRegs;

    // The tape as plain data over this Tape's arrays (valid while it lives): what a device
    // evaluates, and what eval() and evalMaterial() evaluate here.
    TapeView view() const;
    // The arrays behind view(), for copying the tape to a device (gpu/gpu_tape.h); grids()[i]'s
    // view is view().grids[i].
    std::span<const Instr> instructions() const { return m_instrs; }
    std::span<const float> constants() const { return m_consts; }
    const std::vector<std::shared_ptr<const Grid>>& grids() const { return m_grids; }
    float eval(Vec3 p) const;
    // out[i] = f(x[i], y[i], z[i]) for i < n (any n; processed in chunks of kBatchWidth).
    void evalBatch(const float* x, const float* y, const float* z, float* out, int n,
                   BatchScratch& scratch) const;
    MaterialBlend evalMaterial(Vec3 p) const;
    // The one material every point gets, when the tape has a single primitive or grid (a grid
    // without texture coordinates): evalMaterial(p) is single(id, local) everywhere, so renderers
    // whose materials ignore `local` skip it. -1 when the blend varies or needs the point. Found
    // once, when the tape is compiled.
    int uniformMaterial() const { return m_uniformMaterial; }

    float lipschitz() const { return m_lipschitz; }
    const Bounds3& bounds() const { return m_bounds; }
    size_t size() const { return m_instrs.size(); }
    int numPointRegs() const { return m_numPointRegs; }
    int numScalarRegs() const { return m_numScalarRegs; }
    int numCulls() const { return m_numCulls; }
    // The per-cell pruned tapes (null when pruning is off or finds nothing to prune).
    const PrunedTapes* pruned() const { return m_pruned.get(); }
    std::span<const FoldOperands> foldOperands() const { return m_folds; }

  private:
    friend Tape compileTape(const NodePtr& root, const CompileOptions& options);
    friend void addOutsideTape(Tape& tape, const Tape& outside, PrunedTapes& pruned);
    int findUniformMaterial() const;
    void evalChunk(const Instr* instrs, uint32_t count, const float* x, const float* y,
                   const float* z, float* out, int n, BatchScratch& scratch) const;
    // A chunk whose lanes may lie in cells of different pruned tapes: evaluated tape by tape.
    void evalChunkByCell(const float* x, const float* y, const float* z, float* out, int n,
                         BatchScratch& scratch) const;
    // evalBatch's loop over chunks, and its builds for AVX2 and for the x86-64 baseline
    // (exec/simd.h).
    void evalChunks(const float* x, const float* y, const float* z, float* out, int n,
                    BatchScratch& scratch) const;
    void evalChunksAvx2(const float* x, const float* y, const float* z, float* out, int n,
                        BatchScratch& scratch) const;
    void evalChunksBaseline(const float* x, const float* y, const float* z, float* out, int n,
                            BatchScratch& scratch) const;

    std::vector<Instr> m_instrs;
    std::vector<FoldOperands> m_folds;  // per instruction
    std::shared_ptr<const PrunedTapes> m_pruned;
    TapeCells m_cells;  // the view of m_pruned's arrays (empty without)
    std::vector<float> m_consts;
    std::vector<std::shared_ptr<const Grid>> m_grids;  // keeps the views' buffers alive
    std::vector<GridView> m_gridViews;
    int m_numPointRegs = 1;
    int m_numScalarRegs = 1;
    int m_numCulls = 0;
    int m_uniformMaterial = -1;
    uint16_t m_result = 0;
    float m_lipschitz = 1;
    Bounds3 m_bounds;
};

Tape compileTape(const NodePtr& root, const CompileOptions& options = {});

}  // namespace sdft
