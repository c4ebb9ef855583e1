// The analytic field compiled to a flat opcode tape (libfive's tree -> tape -> evaluator).
// One instruction per node; registers hold points (for domain transforms) or scalars (distances).
// Evaluators: eval() for one point (the scalar path), evalBatch() for a structure-of-arrays batch
// (one pass of the interpreter serves many rays), evalMaterial() for the material blend at a hit.
#pragma once

#include <cstdint>
#include <vector>

#include "sdftrace/field/grid.h"
#include "sdftrace/field/node.h"
#include "sdftrace/math/ray.h"

namespace sdft {

enum class Op : uint8_t {
// primitives (primitive_table.h): out(scalar) = f(point a), constants at k
#define SDFT_PRIMITIVE_OP(Kind, ...) Kind,
    SDFT_PRIMITIVES(SDFT_PRIMITIVE_OP)
#undef SDFT_PRIMITIVE_OP
        Grid,  // k[0]: index into the tape's grid views
    // scalar binary: out = op(a, b)
    Union,
    Intersection,
    Difference,
    SmoothUnion,
    SmoothIntersection,
    SmoothDifference,
    Morph,
    // scalar unary
    Complement,     // out = -a
    ScaleValue,     // out = a * k[0]
    RepeatBound,    // out = min(a, neighbour bound of point b)
    FloorByBounds,  // out = max(a, signed distance of point b to the box k[0..5])
    Displace,       // out = a + amplitude * fbm(point b * frequency)
    // point: out(point) = T(point a)
    Translate,
    Rotate,
    ScalePoint,
    RepeatPoint,
    // control: skip the next (smooth) union operand when its bounds (constants k[0..5]) are at
    // least
    // the running minimum in scalar b plus the margin k[6] away from point a; jump to `jump`.
    // See decision 0002.
    CullIfFar,
};

struct Instr {
    Op op;
    uint16_t out = 0, a = 0, b = 0;
    uint32_t k = 0;              // offset of this instruction's constants
    int32_t material = -1;       // for primitives: the material of the surface they make
    uint16_t materialPoint = 0;  // for primitives: the point register of the material's frame
    uint32_t jump = 0;           // CullIfFar: index of the first instruction after the union step
    int32_t cull = -1;           // CullIfFar and the Union it guards: the lane-mask slot in batches
};

struct CompileOptions {
    // Skip union operands whose bounding box is no nearer than the running minimum (decision 0002).
    // The value stays a distance bound with the same zero set; off, the tape equals the tree.
    bool boundsCulling = true;
};

// Up to four materials with weights summing to one (smooth blends and morphs mix materials, as in
// Keinert et al. 2014, §4: CSG operators that also propagate material information).
struct MaterialBlend {
    static constexpr int kMax = 4;
    int id[kMax] = {-1, -1, -1, -1};
    float weight[kMax] = {0, 0, 0, 0};
    // Per entry, for textures: the point in the frame of the node that assigned the material
    // (inside that object's own transforms), and texture coordinates where the surface comes
    // from a grid that stores them (Liktor 2008, §5.5.2).
    Vec3 local[kMax];
    float u[kMax] = {0, 0, 0, 0}, v[kMax] = {0, 0, 0, 0};
    bool hasUv[kMax] = {false, false, false, false};
    int count = 0;

    static MaterialBlend single(int material, Vec3 local = Vec3(0.0f));
    // (1-t) * a + t * b, keeping the kMax heaviest entries; entries of one material average
    // their points and coordinates.
    static MaterialBlend mix(const MaterialBlend& a, const MaterialBlend& b, float t);
};

// Scratch registers for evalBatch; one per thread, reused across calls.
struct BatchScratch {
    std::vector<float> points;    // numPointRegs * 3 * kBatchWidth
    std::vector<float> scalars;   // numScalarRegs * kBatchWidth
    std::vector<uint8_t> culled;  // numCulls * kBatchWidth: lanes that skipped an operand
};

class Tape {
  public:
    static constexpr int kBatchWidth = 64;
    // The scalar evaluator's register files live on the stack: the compiler keeps a tape within
    // them (deeper trees are rejected with an InputError).
    static constexpr int kMaxScalarRegs = 64;
    static constexpr int kMaxPointRegs = 32;

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

  private:
    friend Tape compileTape(const NodePtr& root, const CompileOptions& options);
    template <bool kMaterial>
    float evalScalar(Vec3 p, MaterialBlend* blend) const;
    int findUniformMaterial() const;
    void evalChunk(const float* x, const float* y, const float* z, float* out, int n,
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
