// Tree -> tape compilation: a post-order walk emitting one instruction per node, with registers
// recycled as soon as their last reader is emitted (each value in a tree has exactly one reader).
#include <tbb/task_group.h>

#include <algorithm>
#include <optional>
#include <unordered_map>

#include "sdftrace/core/error.h"
#include "sdftrace/core/macros.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/field/tape_prune.h"

namespace sdft {

namespace {

constexpr int kMaxScalarRegs = Tape::kMaxScalarRegs;
constexpr int kMaxPointRegs = Tape::kMaxPointRegs;

class Compiler {
  public:
    Compiler(std::vector<Instr>& instrs, std::vector<FoldOperands>& folds,
             std::vector<float>& consts, std::vector<std::shared_ptr<const Grid>>& grids,
             const CompileOptions& options)
        : m_instrs(instrs), m_folds(folds), m_consts(consts), m_grids(grids), m_options(options) {}

    uint16_t emit(const Node& n, uint16_t point, int material);
    int pointRegs() const { return m_nextPoint; }
    int scalarRegs() const { return m_nextScalar; }
    int culls() const { return m_numCulls; }

  private:
    uint16_t allocScalar() { return alloc(m_freeScalar, m_nextScalar, kMaxScalarRegs); }
    uint16_t allocPoint() { return alloc(m_freePoint, m_nextPoint, kMaxPointRegs); }
    static uint16_t alloc(std::vector<uint16_t>& freeList, int& next, int limit) {
        if (!freeList.empty()) {
            uint16_t r = freeList.back();
            freeList.pop_back();
            return r;
        }
        if (next >= limit) {
            throw InputError("scene tree is too deeply nested to compile (more than " +
                             std::to_string(limit) + " live registers); flatten unions");
        }
        return static_cast<uint16_t>(next++);
    }
    uint32_t addConsts(const std::vector<float>& k) {
        auto offset = static_cast<uint32_t>(m_consts.size());
        m_consts.insert(m_consts.end(), k.begin(), k.end());
        return offset;
    }
    void push(Op op, uint16_t out, uint16_t a, uint16_t b, uint32_t k, int material = -1) {
        Instr in;
        in.op = op;
        in.out = out;
        in.a = a;
        in.b = b;
        in.k = k;
        in.material = material;
        in.materialPoint = m_materialPoint;
        m_instrs.push_back(in);
        m_folds.emplace_back();
    }
    uint32_t here() const { return static_cast<uint32_t>(m_instrs.size()); }
    uint16_t emitUnion(const Node& n, uint16_t point, int material);
    uint16_t emitPrimitive(const Node& n, uint16_t point, int material);
    uint16_t emitFold(Op op, const Node& n, const std::vector<float>& k, uint16_t point,
                      int material);
    uint16_t emitTransform(const Node& n, uint16_t point, int material);
    uint16_t emitRepeat(const Node& n, uint16_t point, int material);
    uint16_t emitSmoothUnion(const Node& n, uint16_t point, int material);
    // Emits `operand` combined into `acc` by `op`, behind a CullIfFar when culling applies.
    // `fold`: the first instruction of the fold's first operand (FoldOperands).
    void emitGuarded(Op op, uint16_t acc, const Node& operand, uint16_t point, int material,
                     float margin, bool cullable, const std::vector<float>& opConsts,
                     uint32_t fold);
    uint16_t emitPointOp(Op op, uint16_t point, const std::vector<float>& k) {
        uint16_t q = allocPoint();
        push(op, q, point, 0, addConsts(k));
        return q;
    }
    // nodeBounds(n), with each union's bounds kept for the rest of the compile: the operands of a
    // union and their guards ask for the bounds of every union below them, which in a deep
    // hierarchy of unions (the pruned cells' outside tape) is each subtree once per level above
    // it. A union's bounds as nodeBounds takes them (its operands' united in order).
    Bounds3 bounds(const Node& n) {
        if (n.kind != NodeKind::Union) return nodeBounds(n);
        if (const auto it = m_unionBounds.find(&n); it != m_unionBounds.end()) return it->second;
        Bounds3 b;
        for (const NodePtr& c : n.children) b = unite(b, bounds(*c));
        m_unionBounds.emplace(&n, b);
        return b;
    }

    std::vector<Instr>& m_instrs;
    std::vector<FoldOperands>& m_folds;
    std::vector<float>& m_consts;
    std::vector<std::shared_ptr<const Grid>>& m_grids;
    const CompileOptions& m_options;
    int m_numCulls = 0;
    std::vector<uint16_t> m_freeScalar, m_freePoint;
    int m_nextScalar = 0;
    int m_nextPoint = 1;  // point register 0 is the input point
    // The point register of the node that assigned the current material (its frame is the
    // textures' frame); live while its subtree is emitted.
    uint16_t m_materialPoint = 0;
    std::unordered_map<const Node*, Bounds3> m_unionBounds;  // bounds()'s
};

static_assert(static_cast<int>(Op::Grid) - static_cast<int>(Op::Sphere) ==
                  static_cast<int>(NodeKind::Grid) - static_cast<int>(NodeKind::Sphere),
              "NodeKind and Op must list the primitives in the same order");

Op primitiveOp(NodeKind kind) {
    // NodeKind and Op list the primitives in the same order (checked above).
    return static_cast<Op>(static_cast<int>(kind) - static_cast<int>(NodeKind::Sphere) +
                           static_cast<int>(Op::Sphere));
}

uint16_t Compiler::emit(const Node& n, uint16_t point, int material) {
    if (n.material >= 0) {
        material = n.material;
        const uint16_t outer = m_materialPoint;
        m_materialPoint = point;
        Node inner = n;
        inner.material = -1;
        const uint16_t r = emit(inner, point, material);
        m_materialPoint = outer;
        return r;
    }
    if (isPrimitive(n.kind)) return emitPrimitive(n, point, material);
    switch (n.kind) {
        case NodeKind::Union:
            return emitUnion(n, point, material);
        case NodeKind::Intersection:
            return emitFold(Op::Intersection, n, {}, point, material);
        case NodeKind::Difference:
            return emitFold(Op::Difference, n, {}, point, material);
        case NodeKind::SmoothUnion:
            return emitSmoothUnion(n, point, material);
        case NodeKind::SmoothIntersection:
            return emitFold(Op::SmoothIntersection, n, n.params, point, material);
        case NodeKind::SmoothDifference:
            return emitFold(Op::SmoothDifference, n, n.params, point, material);
        case NodeKind::Morph:
            return emitFold(Op::Morph, n, n.params, point, material);
        case NodeKind::Complement: {
            uint16_t r = emit(*n.children[0], point, material);
            push(Op::Complement, r, r, 0, 0);
            return r;
        }
        case NodeKind::Translate:
        case NodeKind::Rotate:
        case NodeKind::Scale:
            return emitTransform(n, point, material);
        case NodeKind::Repeat:
            return emitRepeat(n, point, material);
        case NodeKind::Displace: {
            uint16_t r = emit(*n.children[0], point, material);
            push(Op::Displace, r, r, point, addConsts(n.params));
            push(Op::ScaleValue, r, r, 0, addConsts({displaceScale(n)}));
            return r;
        }
        default:
            break;
    }
    SDFT_CHECK(false && "unhandled node kind");
    return 0;
}

// An analytic primitive (primitive_table.h) or a grid, on the current point register.
uint16_t Compiler::emitPrimitive(const Node& n, uint16_t point, int material) {
    const uint16_t out = allocScalar();
    if (n.kind == NodeKind::Grid) {
        SDFT_CHECK(n.grid != nullptr);  // a pending grid: the scene was not prepared
        m_grids.push_back(n.grid);
        push(Op::Grid, out, point, 0, addConsts({static_cast<float>(m_grids.size() - 1)}),
             material);
    } else {
        push(primitiveOp(n.kind), out, point, 0, addConsts(n.params), material);
    }
    return out;
}

// The children combined left to right by a binary op with constants k.
uint16_t Compiler::emitFold(Op op, const Node& n, const std::vector<float>& k, uint16_t point,
                            int material) {
    const uint32_t fold = here();
    const uint16_t acc = emit(*n.children[0], point, material);
    const uint32_t offset = addConsts(k);
    for (size_t i = 1; i < n.children.size(); ++i) {
        const uint32_t operand = here();
        const uint16_t rhs = emit(*n.children[i], point, material);
        push(op, acc, acc, rhs, offset);
        m_folds.back() = {operand, fold};
        m_freeScalar.push_back(rhs);
    }
    return acc;
}

// Translate, rotate, scale: the child sees the inverse-transformed point.
uint16_t Compiler::emitTransform(const Node& n, uint16_t point, int material) {
    uint16_t q;
    if (n.kind == NodeKind::Rotate) {
        // Store the inverse (transpose): the child sees R^T p.
        std::vector<float> inv(9);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) inv[i * 3 + j] = n.params[j * 3 + i];
        q = emitPointOp(Op::Rotate, point, inv);
    } else {
        q = emitPointOp(n.kind == NodeKind::Translate ? Op::Translate : Op::ScalePoint, point,
                        n.params);
    }
    const uint16_t r = emit(*n.children[0], q, material);
    m_freePoint.push_back(q);
    if (n.kind == NodeKind::Scale) {
        // Liktor 2008, §2.2: f(T^-1 p) has Lipschitz constant L_f / min(s); multiplying by
        // min(s) restores L_f, so the value stays a distance bound in world units.
        const float minScale = std::min({n.params[0], n.params[1], n.params[2]});
        push(Op::ScaleValue, r, r, 0, addConsts({minScale}));
    }
    return r;
}

// The child on the lattice-folded point, bounded by the neighbouring copies' distance.
uint16_t Compiler::emitRepeat(const Node& n, uint16_t point, int material) {
    const uint32_t k = addConsts(n.params);
    const uint16_t q = allocPoint();
    push(Op::RepeatPoint, q, point, 0, k);
    const uint16_t r = emit(*n.children[0], q, material);
    if (!dominatesBounds(*n.children[0])) {
        const Bounds3 b = nodeBounds(*n.children[0]);
        push(Op::FloorByBounds, r, r, q,
             addConsts({b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z}));
    }
    m_freePoint.push_back(q);
    push(Op::RepeatBound, r, r, point, k);
    return r;
}

// A union of operands, each but the first guarded by a CullIfFar when bounds culling is on and the
// operand has finite bounds: if the operand's box is no nearer than the running minimum, its value
// cannot be below the true distance's lower bound we already hold, and it is skipped
// (docs/decisions/0002-bounds-culling.md). Unbounded operands (planes) go first.
uint16_t Compiler::emitUnion(const Node& n, uint16_t point, int material) {
    std::vector<const Node*> order;
    for (const NodePtr& c : n.children) order.push_back(c.get());
    std::stable_partition(order.begin(), order.end(),
                          [this](const Node* c) { return !bounds(*c).finite(); });
    const uint32_t fold = here();
    uint16_t acc = emit(*order[0], point, material);
    for (size_t i = 1; i < order.size(); ++i)
        emitGuarded(Op::Union, acc, *order[i], point, material, 0, true, {}, fold);
    return acc;
}

// A smooth union with radius k ignores an operand b >= acc + k (the blend weight of b is zero),
// so an operand whose value dominates the distance to its box can be skipped when that box is at
// least acc + k away: the result is exactly acc.
uint16_t Compiler::emitSmoothUnion(const Node& n, uint16_t point, int material) {
    const uint32_t fold = here();
    uint16_t acc = emit(*n.children[0], point, material);
    float k = n.params[0];
    for (size_t i = 1; i < n.children.size(); ++i) {
        emitGuarded(Op::SmoothUnion, acc, *n.children[i], point, material, k,
                    dominatesBounds(*n.children[i]), n.params, fold);
    }
    return acc;
}

void Compiler::emitGuarded(Op op, uint16_t acc, const Node& operand, uint16_t point, int material,
                           float margin, bool cullable, const std::vector<float>& opConsts,
                           uint32_t fold) {
    Bounds3 box = bounds(operand);
    bool cull = m_options.boundsCulling && cullable && box.finite() && !box.empty();
    size_t guard = m_instrs.size();
    int slot = -1;
    if (cull) {
        slot = m_numCulls++;
        push(Op::CullIfFar, 0, point, acc,
             addConsts({box.lo.x, box.lo.y, box.lo.z, box.hi.x, box.hi.y, box.hi.z, margin}));
        m_instrs.back().cull = slot;
    }
    const uint32_t begin = here();
    uint16_t rhs = emit(operand, point, material);
    push(op, acc, acc, rhs, addConsts(opConsts));
    m_instrs.back().cull = slot;
    m_folds.back() = {begin, fold};
    m_freeScalar.push_back(rhs);
    if (cull) m_instrs[guard].jump = static_cast<uint32_t>(m_instrs.size());
}

}  // namespace

namespace {
// The operands as a bounding volume hierarchy of nested unions (median splits along the longest
// axis of their boxes' centres, each centre computed once): compiled with bounds culling, each
// group is skipped by its box.
struct Placed {
    NodePtr node;
    Vec3 centre;
};
NodePtr unionHierarchy(std::vector<Placed>::iterator first, std::vector<Placed>::iterator last) {
    const size_t n = static_cast<size_t>(last - first);
    if (n <= 4) {
        std::vector<NodePtr> ops;
        for (auto it = first; it != last; ++it) ops.push_back(it->node);
        return n == 1 ? ops[0] : node::unite(ops);
    }
    Bounds3 centres;
    for (auto it = first; it != last; ++it) centres.include(it->centre);
    const Vec3 e = centres.extent();
    const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
    const auto mid = first + static_cast<std::ptrdiff_t>(n / 2);
    std::nth_element(first, mid, last, [axis](const Placed& a, const Placed& b) {
        return a.centre[axis] < b.centre[axis];
    });
    return node::unite({unionHierarchy(first, mid), unionHierarchy(mid, last)});
}

// The pruned tapes' arrays as the view reads them.
TapeCells cellsView(const PrunedTapes& p) {
    TapeCells c;
    c.instrs = p.instrs.data();
    c.spans = p.spans.data();
    c.cellTape = p.cellTape.data();
    c.outside = p.outsideTape;
    c.lo = p.box.lo;
    const Vec3 extent = p.box.extent();
    for (int a = 0; a < 3; ++a) {
        c.res[a] = p.res[a];
        c.invCell[a] = static_cast<float>(p.res[a]) / extent[a];
    }
    return c;
}
}  // namespace

namespace {

// The tape of points outside the pruned cells' box (PrunedTapes::outsideTape) for a top-level
// union with bounds culling: its unbounded operands (planes) first, then the others as a
// hierarchy of unions each guarded by its box. Culling skips a group whose box is no nearer than
// the running minimum, so the value is the whole tape's minimum (exactly so for operands whose
// value dominates the distance to their box), at a cost that grows with log N, not N. Null for
// fewer than eight bounded operands.
std::optional<Tape> outsideTapeOf(const Node& root) {
    std::vector<NodePtr> planes;
    std::vector<Placed> bounded;
    for (const NodePtr& c : root.children) {
        const Bounds3 b = nodeBounds(*c);
        if (b.finite())
            bounded.push_back({c, (b.lo + b.hi) * 0.5f});
        else
            planes.push_back(c);
    }
    if (bounded.size() < 8) return std::nullopt;
    planes.push_back(unionHierarchy(bounded.begin(), bounded.end()));
    return compileTape(planes.size() == 1 ? planes[0] : node::unite(planes),
                       {.boundsCulling = true, .pruning = false});
}

}  // namespace

// The outside tape after the cells' tapes; its constants go after the tape's.
void addOutsideTape(Tape& tape, const Tape& outside, PrunedTapes& pruned) {
    if (outside.m_numCulls > tape.m_numCulls) tape.m_numCulls = outside.m_numCulls;
    const auto base = static_cast<uint32_t>(tape.m_consts.size());
    tape.m_consts.insert(tape.m_consts.end(), outside.m_consts.begin(), outside.m_consts.end());
    pruned.outsideTape = static_cast<int32_t>(pruned.spans.size() / 2);
    pruned.spans.push_back(static_cast<uint32_t>(pruned.instrs.size()));
    pruned.spans.push_back(static_cast<uint32_t>(outside.m_instrs.size()));
    for (Instr in : outside.m_instrs) {  // jumps count from the tape's first instruction
        in.k += base;
        pruned.instrs.push_back(in);
    }
    tape.m_numScalarRegs = std::max(tape.m_numScalarRegs, outside.m_numScalarRegs);
    tape.m_numPointRegs = std::max(tape.m_numPointRegs, outside.m_numPointRegs);
}

Tape compileTape(const NodePtr& root, const CompileOptions& options) {
    SDFT_CHECK(root != nullptr);
    Tape tape;
    Compiler compiler(tape.m_instrs, tape.m_folds, tape.m_consts, tape.m_grids, options);
    tape.m_result = compiler.emit(*root, 0, root->material >= 0 ? root->material : 0);
    tape.m_numPointRegs = compiler.pointRegs();
    tape.m_numScalarRegs = compiler.scalarRegs();
    tape.m_numCulls = compiler.culls();
    for (const auto& g : tape.m_grids) tape.m_gridViews.push_back(g->view());
    tape.m_lipschitz = lipschitzBound(*root);
    tape.m_bounds = nodeBounds(*root);
    tape.m_uniformMaterial = tape.findUniformMaterial();
    if (options.pruning) {
        // The outside tape (of a top-level union, with bounds culling) is compiled while the
        // cells are built: the two do not depend on each other, and the cells' build leaves
        // cores idle at its top levels.
        std::optional<Tape> outside;
        tbb::task_group outsideTask;
        if (options.boundsCulling && root->kind == NodeKind::Union && tape.m_grids.empty() &&
            mayPrune(tape))
            outsideTask.run([&] { outside = outsideTapeOf(*root); });
        std::shared_ptr<PrunedTapes> pruned = buildPrunedTapes(tape, *root);
        outsideTask.wait();
        if (pruned && outside) addOutsideTape(tape, *outside, *pruned);
        if (pruned) tape.m_cells = cellsView(*pruned);
        tape.m_pruned = std::move(pruned);
    }
    return tape;
}

}  // namespace sdft
