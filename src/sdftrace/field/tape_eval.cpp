// The batch evaluator (structure of arrays) and the Tape's view; the scalar evaluator is in
// field/tape_view.h, whose per-op functions both share.
#include <algorithm>

#include "sdftrace/core/macros.h"
#include "sdftrace/exec/simd.h"
#include "sdftrace/field/grid_distance.h"
#include "sdftrace/field/lane_groups.h"
#include "sdftrace/field/noise.h"
#include "sdftrace/field/operators.h"
#include "sdftrace/field/primitives.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/field/transforms.h"

namespace sdft {

TapeView Tape::view() const {
    TapeView v;
    v.instrs = m_instrs.data();
    v.consts = m_consts.data();
    v.grids = m_gridViews.data();
    v.count = static_cast<uint32_t>(m_instrs.size());
    v.result = m_result;
    v.numScalarRegs = static_cast<uint16_t>(m_numScalarRegs);
    v.numPointRegs = static_cast<uint16_t>(m_numPointRegs);
    v.lipschitz = m_lipschitz;
    v.bounds = m_bounds;
    v.cells = m_cells;
    return v;
}

float Tape::eval(Vec3 p) const { return evalTape(view(), p); }

int Tape::findUniformMaterial() const {
    const Instr* leaf = nullptr;
    for (const Instr& in : m_instrs) {
        if (in.op > Op::Grid) continue;
        if (leaf) return -1;
        leaf = &in;
    }
    if (!leaf || leaf->material < 0) return -1;
    if (leaf->op == Op::Grid && m_gridViews[static_cast<size_t>(m_consts[leaf->k])].texcoords)
        return -1;
    return leaf->material;
}

MaterialBlend Tape::evalMaterial(Vec3 p) const {
    MaterialBlend blend;
    evalTapeAt<kMaxScalarRegs>(view(), p, &blend);
    return blend;
}

void Tape::evalBatch(const float* x, const float* y, const float* z, float* out, int n,
                     BatchScratch& scratch) const {
    size_t needP = static_cast<size_t>(m_numPointRegs) * 3 * kBatchWidth;
    size_t needS = static_cast<size_t>(m_numScalarRegs) * kBatchWidth;
    if (scratch.points.size() < needP) scratch.points.resize(needP);
    if (scratch.scalars.size() < needS) scratch.scalars.resize(needS);
    size_t needC = static_cast<size_t>(m_numCulls) * kBatchWidth;
    if (scratch.culled.size() < needC) scratch.culled.resize(needC);
    if (m_pruned && scratch.gout.size() < kBatchWidth) {
        for (auto* v : {&scratch.gx, &scratch.gy, &scratch.gz, &scratch.gout})
            v->resize(kBatchWidth);
        scratch.laneTape.resize(kBatchWidth);
        scratch.order.resize(kBatchWidth);
    }
    if (useAvx2())
        evalChunksAvx2(x, y, z, out, n, scratch);
    else
        evalChunksBaseline(x, y, z, out, n, scratch);
}

void Tape::evalChunks(const float* x, const float* y, const float* z, float* out, int n,
                      BatchScratch& scratch) const {
    for (int start = 0; start < n; start += kBatchWidth) {
        const int m = std::min(kBatchWidth, n - start);
        if (m_pruned)
            evalChunkByCell(x + start, y + start, z + start, out + start, m, scratch);
        else
            evalChunk(m_instrs.data(), static_cast<uint32_t>(m_instrs.size()), x + start, y + start,
                      z + start, out + start, m, scratch);
    }
}

// The lanes grouped by their cell's tape (primary rays of a tile mostly share one), each group
// evaluated by its tape; lanes outside the cells' box by the outside tape (or the whole one).
void Tape::evalChunkByCell(const float* x, const float* y, const float* z, float* out, int n,
                           BatchScratch& scratch) const {
    const TapeView v = view();
    uint32_t* laneTape = scratch.laneTape.data();
    bool same = true;
    for (int l = 0; l < n; ++l) {
        laneTape[l] = m_cells.tapeOf(Vec3(x[l], y[l], z[l]));
        same &= laneTape[l] == laneTape[0];
    }
    const Instr* first;
    uint32_t count;
    if (same) {
        v.tapeSpan(laneTape[0], first, count);
        evalChunk(first, count, x, y, z, out, n, scratch);
        return;
    }
    // Group by group: gather the lanes of the first tape not yet done, evaluate, scatter.
    uint32_t* order = scratch.order.data();
    float *gx = scratch.gx.data(), *gy = scratch.gy.data(), *gz = scratch.gz.data(),
          *go = scratch.gout.data();
    for (int from = 0; from < n; ++from) {
        uint32_t t;
        const int m = takeLaneGroup(laneTape, from, n, order, t);
        if (m == 0) continue;
        for (int g = 0; g < m; ++g) gx[g] = x[order[g]], gy[g] = y[order[g]], gz[g] = z[order[g]];
        v.tapeSpan(t, first, count);
        evalChunk(first, count, gx, gy, gz, go, m, scratch);
        for (int g = 0; g < m; ++g) out[order[g]] = go[g];
    }
}

SDFT_TARGET_AVX2 void Tape::evalChunksAvx2(const float* x, const float* y, const float* z,
                                           float* out, int n, BatchScratch& scratch) const {
    evalChunks(x, y, z, out, n, scratch);
}

SDFT_TARGET_BASELINE void Tape::evalChunksBaseline(const float* x, const float* y, const float* z,
                                                   float* out, int n, BatchScratch& scratch) const {
    evalChunks(x, y, z, out, n, scratch);
}

// One switch over every opcode, deliberately: split into a function per kind of instruction
// (always inlined) it ran 2.8% more instructions on examples/many_blend.json (callgrind, issue
// 13), and this loop is most of a render's time.
void Tape::evalChunk(const Instr* instrs, uint32_t count, const float* x, const float* y,
                     const float* z, float* out, int n, BatchScratch& scratch) const {
    constexpr int W = kBatchWidth;
    float* points = scratch.points.data();
    float* scalars = scratch.scalars.data();
    auto px = [&](int r) { return points + (r * 3 + 0) * W; };
    auto py = [&](int r) { return points + (r * 3 + 1) * W; };
    auto pz = [&](int r) { return points + (r * 3 + 2) * W; };
    auto sr = [&](int r) { return scalars + r * W; };
    std::copy(x, x + n, px(0));
    std::copy(y, y + n, py(0));
    std::copy(z, z + n, pz(0));
    const float* consts = m_consts.data();

#define SDFT_PRIMITIVE_BATCH(Kind, name, eval, ...)                            \
    case Op::Kind: {                                                           \
        const float *ax = px(in.a), *ay = py(in.a), *az = pz(in.a);            \
        float* o = sr(in.out);                                                 \
        for (int l = 0; l < n; ++l) o[l] = eval(Vec3(ax[l], ay[l], az[l]), k); \
        break;                                                                 \
    }

    TapeWalk walk(instrs, count, m_instrs.data());
    for (uint32_t pc = 0; const Instr* next = walk.at(pc); ++pc) {
        const Instr& in = *next;
        const float* k = consts + in.k;
        switch (in.op) {
            case Op::Run:  // TapeWalk follows it
                break;
            case Op::CullIfFar: {
                // Per lane as in the scalar path (compared squared, branch-free so it vectorizes);
                // the operand is skipped when every lane skips it.
                uint8_t* mask = scratch.culled.data() + static_cast<size_t>(in.cull) * W;
                const float *ax = px(in.a), *ay = py(in.a), *az = pz(in.a), *acc = sr(in.b);
                int skipped = 0;
                for (int l = 0; l < n; ++l) {
                    float dx = maxf(maxf(k[0] - ax[l], ax[l] - k[3]), 0.0f);
                    float dy = maxf(maxf(k[1] - ay[l], ay[l] - k[4]), 0.0f);
                    float dz = maxf(maxf(k[2] - az[l], az[l] - k[5]), 0.0f);
                    float t = acc[l] + k[6];
                    uint8_t skip = (t <= 0.0f) | (dx * dx + dy * dy + dz * dz >= t * t);
                    mask[l] = skip;
                    skipped += skip;
                }
                if (skipped == n) pc = in.jump - 1;
                break;
            }
                SDFT_PRIMITIVES(SDFT_PRIMITIVE_BATCH)
            case Op::Grid: {
                const GridView& g = m_gridViews[static_cast<size_t>(k[0])];
                const float *ax = px(in.a), *ay = py(in.a), *az = pz(in.a);
                float* o = sr(in.out);
                for (int l = 0; l < n; ++l)
                    o[l] = tape_ops::gridValue(g, Vec3(ax[l], ay[l], az[l]));
                break;
            }
            case Op::Union: {
                float *o = sr(in.out), *a = sr(in.a), *b = sr(in.b);
                if (in.cull >= 0) {
                    const uint8_t* mask = scratch.culled.data() + static_cast<size_t>(in.cull) * W;
                    for (int l = 0; l < n; ++l) o[l] = mask[l] ? a[l] : minf(a[l], b[l]);
                } else {
                    for (int l = 0; l < n; ++l) o[l] = minf(a[l], b[l]);
                }
                break;
            }
            case Op::Intersection: {
                float *o = sr(in.out), *a = sr(in.a), *b = sr(in.b);
                for (int l = 0; l < n; ++l) o[l] = maxf(a[l], b[l]);
                break;
            }
            case Op::Difference:
            case Op::SmoothUnion:
            case Op::SmoothIntersection:
            case Op::SmoothDifference:
            case Op::Morph: {
                float *o = sr(in.out), *a = sr(in.a), *b = sr(in.b);
                float h;
                if (in.cull >= 0) {  // a culled smooth-union operand: masked lanes keep a
                    const uint8_t* mask = scratch.culled.data() + static_cast<size_t>(in.cull) * W;
                    for (int l = 0; l < n; ++l)
                        o[l] = mask[l] ? a[l] : tape_ops::binary(in.op, a[l], b[l], k, h);
                } else {
                    for (int l = 0; l < n; ++l) o[l] = tape_ops::binary(in.op, a[l], b[l], k, h);
                }
                break;
            }
            case Op::Complement: {
                float *o = sr(in.out), *a = sr(in.a);
                for (int l = 0; l < n; ++l) o[l] = -a[l];
                break;
            }
            case Op::Copy:
                std::copy(sr(in.a), sr(in.a) + n, sr(in.out));
                break;
            case Op::ScaleValue: {
                float *o = sr(in.out), *a = sr(in.a);
                for (int l = 0; l < n; ++l) o[l] = a[l] * k[0];
                break;
            }
            case Op::FloorByBounds: {
                float *o = sr(in.out), *a = sr(in.a);
                const float *bx = px(in.b), *by = py(in.b), *bz = pz(in.b);
                for (int l = 0; l < n; ++l)
                    o[l] = xform::floorByBounds(a[l], Vec3(bx[l], by[l], bz[l]), k);
                break;
            }
            case Op::RepeatBound:
            case Op::Displace: {
                float *o = sr(in.out), *a = sr(in.a);
                const float *bx = px(in.b), *by = py(in.b), *bz = pz(in.b);
                for (int l = 0; l < n; ++l) {
                    Vec3 q(bx[l], by[l], bz[l]);
                    o[l] = in.op == Op::RepeatBound ? minf(a[l], xform::repeatNeighbourBound(q, k))
                                                    : a[l] + tape_ops::displacement(q, k);
                }
                break;
            }
            case Op::Translate:
            case Op::Rotate:
            case Op::ScalePoint:
            case Op::RepeatPoint: {
                const float *ax = px(in.a), *ay = py(in.a), *az = pz(in.a);
                float *ox = px(in.out), *oy = py(in.out), *oz = pz(in.out);
                for (int l = 0; l < n; ++l) {
                    Vec3 q = tape_ops::pointOp(in.op, Vec3(ax[l], ay[l], az[l]), k);
                    ox[l] = q.x;
                    oy[l] = q.y;
                    oz[l] = q.z;
                }
                break;
            }
        }
    }
#undef SDFT_PRIMITIVE_BATCH
    std::copy(sr(m_result), sr(m_result) + n, out);
}

}  // namespace sdft
