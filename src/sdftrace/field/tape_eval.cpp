// Tape evaluators: scalar (one point, optional material tracking) and batch (structure of arrays).
// Both dispatch to the same per-op functions in primitives.h / operators.h / transforms.h.
#include <algorithm>

#include "sdftrace/core/macros.h"
#include "sdftrace/exec/simd.h"
#include "sdftrace/field/grid_distance.h"
#include "sdftrace/field/noise.h"
#include "sdftrace/field/operators.h"
#include "sdftrace/field/primitives.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/field/transforms.h"

namespace sdft {

namespace {
constexpr int kMaxScalarRegs = Tape::kMaxScalarRegs;
constexpr int kMaxPointRegs = Tape::kMaxPointRegs;

float evalPrimitive(Op op, Vec3 p, const float* k) {
    switch (op) {
#define SDFT_PRIMITIVE_EVAL(Kind, name, eval, ...) \
    case Op::Kind:                                 \
        return eval(p, k);
        SDFT_PRIMITIVES(SDFT_PRIMITIVE_EVAL)
#undef SDFT_PRIMITIVE_EVAL
        default:
            return 0;
    }
}

// Binary scalar ops. `h` returns the weight of `a` for material blending.
inline float evalBinary(Op op, float a, float b, const float* k, float& h) {
    switch (op) {
        case Op::Union:
            h = a <= b ? 1.f : 0.f;
            return minf(a, b);
        case Op::Intersection:
            h = a >= b ? 1.f : 0.f;
            return maxf(a, b);
        case Op::Difference:
            h = a >= -b ? 1.f : 0.f;
            return maxf(a, -b);
        case Op::SmoothUnion:
            return ops::smoothMin(a, b, k[0], h);
        case Op::SmoothIntersection:
            return ops::smoothMax(a, b, k[0], h);
        case Op::SmoothDifference:
            return ops::smoothMax(a, -b, k[0], h);
        case Op::Morph:
            h = 1 - k[0];
            return (1 - k[0]) * a + k[0] * b;
        default:
            h = 1;
            return a;
    }
}

inline Vec3 evalPointOp(Op op, Vec3 p, const float* k) {
    switch (op) {
        case Op::Translate:
            return p - Vec3(k[0], k[1], k[2]);
        case Op::Rotate: {
            return {k[0] * p.x + k[1] * p.y + k[2] * p.z, k[3] * p.x + k[4] * p.y + k[5] * p.z,
                    k[6] * p.x + k[7] * p.y + k[8] * p.z};
        }
        case Op::ScalePoint:
            return p / Vec3(k[0], k[1], k[2]);
        case Op::RepeatPoint:
            return xform::repeatPoint(p, k);
        default:
            return p;
    }
}

// CullIfFar's test, as the batch loop computes it: box distance >= acc + margin, squared.
inline bool cullSkips(Vec3 p, float acc, const float* k) {
    float dx = maxf(maxf(k[0] - p.x, p.x - k[3]), 0.0f);
    float dy = maxf(maxf(k[1] - p.y, p.y - k[4]), 0.0f);
    float dz = maxf(maxf(k[2] - p.z, p.z - k[5]), 0.0f);
    float t = acc + k[6];
    return (t <= 0.0f) | (dx * dx + dy * dy + dz * dz >= t * t);
}

// A grid's value, normalized by its Lipschitz bound so it is 1-Lipschitz like the primitives.
inline float gridValue(const GridView& g, Vec3 p) { return gridDistanceBound(g, p); }

inline float displacement(Vec3 p, const float* k) {
    return k[0] * noise::fbm(p * k[1], static_cast<int>(k[2]), k[3]);
}
}  // namespace

MaterialBlend MaterialBlend::single(int material, Vec3 local) {
    MaterialBlend b;
    b.id[0] = material;
    b.weight[0] = 1;
    b.local[0] = local;
    b.count = 1;
    return b;
}

MaterialBlend MaterialBlend::mix(const MaterialBlend& a, const MaterialBlend& b, float t) {
    if (t <= 0) return a;
    if (t >= 1) return b;
    struct Entry {
        int id;
        float w;
        Vec3 local;
        float u, v, uvWeight;
    };
    Entry e[2 * kMax];
    int n = 0;
    auto add = [&](const MaterialBlend& m, int i, float w) {
        const float uw = m.hasUv[i] ? w : 0.0f;
        for (int j = 0; j < n; ++j) {
            if (e[j].id == m.id[i]) {
                e[j].local += m.local[i] * w;
                e[j].u += m.u[i] * uw;
                e[j].v += m.v[i] * uw;
                e[j].uvWeight += uw;
                e[j].w += w;
                return;
            }
        }
        e[n++] = {m.id[i], w, m.local[i] * w, m.u[i] * uw, m.v[i] * uw, uw};
    };
    for (int i = 0; i < a.count; ++i) add(a, i, a.weight[i] * (1 - t));
    for (int i = 0; i < b.count; ++i) add(b, i, b.weight[i] * t);
    // Keep the heaviest kMax entries, renormalized.
    MaterialBlend out;
    float total = 0;
    for (int slot = 0; slot < kMax && slot < n; ++slot) {
        int best = slot;
        for (int i = slot + 1; i < n; ++i)
            if (e[i].w > e[best].w) best = i;
        std::swap(e[slot], e[best]);
        const Entry& x = e[slot];
        out.id[slot] = x.id;
        out.weight[slot] = x.w;
        out.local[slot] = x.w > 0 ? x.local / x.w : Vec3(0.0f);
        out.hasUv[slot] = x.uvWeight > 0;
        if (out.hasUv[slot]) {
            out.u[slot] = x.u / x.uvWeight;
            out.v[slot] = x.v / x.uvWeight;
        }
        total += x.w;
        out.count = slot + 1;
    }
    for (int i = 0; i < out.count; ++i) out.weight[i] /= total;
    return out;
}

template <bool kMaterial>
float Tape::evalScalar(Vec3 p, MaterialBlend* blend) const {
    float s[kMaxScalarRegs];
    Vec3 pts[kMaxPointRegs];
    MaterialBlend mats[kMaterial ? kMaxScalarRegs : 1];
    pts[0] = p;
    const float* consts = m_consts.data();
    const size_t count = m_instrs.size();
    for (size_t pc = 0; pc < count; ++pc) {
        const Instr& in = m_instrs[pc];
        const float* k = consts + in.k;
        Op op = in.op;
        if (op == Op::CullIfFar) {
            if (cullSkips(pts[in.a], s[in.b], k)) pc = in.jump - 1;
            continue;
        }
        if (op <= Op::Grid) {
            s[in.out] = op == Op::Grid
                            ? gridValue(m_gridViews[static_cast<size_t>(k[0])], pts[in.a])
                            : evalPrimitive(op, pts[in.a], k);
            if constexpr (kMaterial) {
                mats[in.out] = MaterialBlend::single(in.material, pts[in.materialPoint]);
                if (op == Op::Grid) {
                    const GridView& g = m_gridViews[static_cast<size_t>(k[0])];
                    if (g.texcoords)
                        mats[in.out].hasUv[0] =
                            g.texcoordsAt(pts[in.a], mats[in.out].u[0], mats[in.out].v[0]);
                }
            }
        } else if (op <= Op::Morph) {
            float h;
            s[in.out] = evalBinary(op, s[in.a], s[in.b], k, h);
            if constexpr (kMaterial)
                mats[in.out] = MaterialBlend::mix(mats[in.a], mats[in.b], 1 - h);
        } else if (op == Op::Complement) {
            s[in.out] = -s[in.a];
        } else if (op == Op::ScaleValue) {
            s[in.out] = s[in.a] * k[0];
        } else if (op == Op::RepeatBound) {
            s[in.out] = minf(s[in.a], xform::repeatNeighbourBound(pts[in.b], k));
        } else if (op == Op::FloorByBounds) {
            s[in.out] = xform::floorByBounds(s[in.a], pts[in.b], k);
        } else if (op == Op::Displace) {
            s[in.out] = s[in.a] + displacement(pts[in.b], k);
        } else {
            pts[in.out] = evalPointOp(op, pts[in.a], k);
        }
    }
    if constexpr (kMaterial) *blend = mats[m_result];
    return s[m_result];
}

float Tape::eval(Vec3 p) const { return evalScalar<false>(p, nullptr); }

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
    evalScalar<true>(p, &blend);
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
    if (useAvx2())
        evalChunksAvx2(x, y, z, out, n, scratch);
    else
        evalChunksBaseline(x, y, z, out, n, scratch);
}

void Tape::evalChunks(const float* x, const float* y, const float* z, float* out, int n,
                      BatchScratch& scratch) const {
    for (int start = 0; start < n; start += kBatchWidth)
        evalChunk(x + start, y + start, z + start, out + start, std::min(kBatchWidth, n - start),
                  scratch);
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
void Tape::evalChunk(const float* x, const float* y, const float* z, float* out, int n,
                     BatchScratch& scratch) const {
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

    const size_t count = m_instrs.size();
    for (size_t pc = 0; pc < count; ++pc) {
        const Instr& in = m_instrs[pc];
        const float* k = consts + in.k;
        switch (in.op) {
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
                for (int l = 0; l < n; ++l) o[l] = gridValue(g, Vec3(ax[l], ay[l], az[l]));
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
                        o[l] = mask[l] ? a[l] : evalBinary(in.op, a[l], b[l], k, h);
                } else {
                    for (int l = 0; l < n; ++l) o[l] = evalBinary(in.op, a[l], b[l], k, h);
                }
                break;
            }
            case Op::Complement: {
                float *o = sr(in.out), *a = sr(in.a);
                for (int l = 0; l < n; ++l) o[l] = -a[l];
                break;
            }
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
                                                    : a[l] + displacement(q, k);
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
                    Vec3 q = evalPointOp(in.op, Vec3(ax[l], ay[l], az[l]), k);
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
