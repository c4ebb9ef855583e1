#include "sdftrace/field/node.h"

#include <algorithm>
#include <cmath>

#include "sdftrace/core/macros.h"
#include "sdftrace/field/grid.h"
#include "sdftrace/field/grid_distance.h"
#include "sdftrace/field/noise.h"
#include "sdftrace/field/operators.h"
#include "sdftrace/field/primitives.h"
#include "sdftrace/field/transforms.h"

namespace sdft {

bool isPrimitive(NodeKind kind) { return kind <= NodeKind::Grid; }

const char* nodeKindName(NodeKind kind) {
    switch (kind) {
#define SDFT_PRIMITIVE_NAME(Kind, name, ...) \
    case NodeKind::Kind:                     \
        return name;
        SDFT_PRIMITIVES(SDFT_PRIMITIVE_NAME)
#undef SDFT_PRIMITIVE_NAME
        case NodeKind::Grid:
            return "grid";
        case NodeKind::Union:
            return "union";
        case NodeKind::Intersection:
            return "intersection";
        case NodeKind::Difference:
            return "difference";
        case NodeKind::Complement:
            return "complement";
        case NodeKind::SmoothUnion:
            return "smooth_union";
        case NodeKind::SmoothIntersection:
            return "smooth_intersection";
        case NodeKind::SmoothDifference:
            return "smooth_difference";
        case NodeKind::Morph:
            return "morph";
        case NodeKind::Translate:
            return "translate";
        case NodeKind::Rotate:
            return "rotate";
        case NodeKind::Scale:
            return "scale";
        case NodeKind::Repeat:
            return "repeat";
        case NodeKind::Displace:
            return "displace";
    }
    return "?";
}

namespace node {
namespace {
NodePtr make(NodeKind kind, std::vector<float> params, std::vector<NodePtr> children = {}) {
    auto n = std::make_shared<Node>();
    n->kind = kind;
    n->params = std::move(params);
    n->children = std::move(children);
    return n;
}
}  // namespace

NodePtr sphere(float r) { return make(NodeKind::Sphere, {r}); }
NodePtr box(Vec3 h) { return make(NodeKind::Box, {h.x, h.y, h.z}); }
NodePtr roundBox(Vec3 h, float r) { return make(NodeKind::RoundBox, {h.x, h.y, h.z, r}); }
NodePtr torus(float R, float r) { return make(NodeKind::Torus, {R, r}); }
NodePtr capsule(Vec3 a, Vec3 b, float r) {
    return make(NodeKind::Capsule, {a.x, a.y, a.z, b.x, b.y, b.z, r});
}
NodePtr cylinder(float r, float halfHeight) { return make(NodeKind::Cylinder, {r, halfHeight}); }
NodePtr cone(float r, float h) { return make(NodeKind::Cone, {r, h}); }
NodePtr plane(Vec3 n, float d) {
    Vec3 u = normalize(n);
    return make(NodeKind::Plane, {u.x, u.y, u.z, d});
}
NodePtr ellipsoid(Vec3 r) { return make(NodeKind::Ellipsoid, {r.x, r.y, r.z}); }
NodePtr octahedron(float s) { return make(NodeKind::Octahedron, {s}); }
NodePtr dodecahedron(float r) { return make(NodeKind::Dodecahedron, {r}); }

NodePtr blobs(const std::vector<Blob>& list, float threshold) {
    SDFT_CHECK(!list.empty());
    float lipschitz = 0;
    for (const Blob& b : list) lipschitz += b.strength * prim::kBlobFalloffMaxSlope / b.radius;
    std::vector<float> k = {threshold, 1.0f / lipschitz, static_cast<float>(list.size())};
    for (const Blob& b : list) {
        k.insert(k.end(), {b.center.x, b.center.y, b.center.z, b.radius, b.strength});
    }
    return make(NodeKind::Blobs, std::move(k));
}

NodePtr grid(std::shared_ptr<const Grid> g) {
    SDFT_CHECK(g != nullptr);
    auto n = std::make_shared<Node>();
    n->kind = NodeKind::Grid;
    n->grid = std::move(g);
    return n;
}

NodePtr gridAsset(int index) {
    SDFT_CHECK(index >= 0);
    auto n = std::make_shared<Node>();
    n->kind = NodeKind::Grid;
    n->asset = index;
    return n;
}

NodePtr unite(std::vector<NodePtr> c) {
    SDFT_CHECK(!c.empty());
    return make(NodeKind::Union, {}, std::move(c));
}
NodePtr intersect(std::vector<NodePtr> c) {
    SDFT_CHECK(!c.empty());
    return make(NodeKind::Intersection, {}, std::move(c));
}
NodePtr subtract(NodePtr a, NodePtr b) { return make(NodeKind::Difference, {}, {a, b}); }
NodePtr complement(NodePtr a) { return make(NodeKind::Complement, {}, {a}); }
NodePtr smoothUnion(NodePtr a, NodePtr b, float k) {
    return make(NodeKind::SmoothUnion, {k}, {a, b});
}
NodePtr smoothIntersection(NodePtr a, NodePtr b, float k) {
    return make(NodeKind::SmoothIntersection, {k}, {a, b});
}
NodePtr smoothDifference(NodePtr a, NodePtr b, float k) {
    return make(NodeKind::SmoothDifference, {k}, {a, b});
}
NodePtr morph(NodePtr a, NodePtr b, float w) { return make(NodeKind::Morph, {w}, {a, b}); }

NodePtr translate(NodePtr c, Vec3 t) { return make(NodeKind::Translate, {t.x, t.y, t.z}, {c}); }
NodePtr rotate(NodePtr c, const Mat3& r) {
    std::vector<float> k;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) k.push_back(r.m[i][j]);
    return make(NodeKind::Rotate, std::move(k), {c});
}
NodePtr scale(NodePtr c, Vec3 s) { return make(NodeKind::Scale, {s.x, s.y, s.z}, {c}); }

NodePtr repeat(NodePtr c, Vec3 cell, Vec3 count) {
    Bounds3 b = nodeBounds(*c);
    float gap = 1e30f;
    for (int i = 0; i < 3; ++i) {
        if (count[i] <= 0) continue;
        float extent = maxf(std::fabs(b.lo[i]), std::fabs(b.hi[i]));
        gap = minf(gap, 0.5f * cell[i] - extent);
    }
    Vec3 reach = cell * count;
    Bounds3 array{b.lo - reach, b.hi + reach};
    return make(NodeKind::Repeat,
                {cell.x, cell.y, cell.z, count.x, count.y, count.z, gap, array.lo.x, array.lo.y,
                 array.lo.z, array.hi.x, array.hi.y, array.hi.z},
                {c});
}

NodePtr displace(NodePtr c, float amplitude, float frequency, int octaves, float gain) {
    return make(NodeKind::Displace, {amplitude, frequency, static_cast<float>(octaves), gain}, {c});
}

NodePtr withMaterial(NodePtr n, int material) {
    auto copy = std::make_shared<Node>(*n);
    copy->material = material;
    return copy;
}
}  // namespace node

// Liktor 2008, §2.2: union, intersection and complement keep the larger Lipschitz constant of
// their operands; a transform multiplies it by the Lipschitz constant of its inverse. The scale
// node multiplies its value by min(s), which cancels that factor (1/min s), so it keeps the child's
// bound.
float lipschitzBound(const Node& n) {
    auto childL = [&](size_t i) { return lipschitzBound(*n.children[i]); };
    switch (n.kind) {
        case NodeKind::Union:
        case NodeKind::Intersection:
        case NodeKind::Difference:
        case NodeKind::SmoothUnion:
        case NodeKind::SmoothIntersection:
        case NodeKind::SmoothDifference: {
            float l = 0;
            for (size_t i = 0; i < n.children.size(); ++i) l = std::max(l, childL(i));
            return l;
        }
        case NodeKind::Morph: {
            float w = n.params[0];
            return (1 - w) * childL(0) + w * childL(1);
        }
        case NodeKind::Complement:
        case NodeKind::Translate:
        case NodeKind::Rotate:
        case NodeKind::Scale:
            return childL(0);
        case NodeKind::Repeat:  // the neighbour and box bounds are 1-Lipschitz
            return std::max(childL(0), 1.0f);
        case NodeKind::Displace:
            return childL(0);  // renormalized, see displaceScale()
        default:
            return 1.0f;  // every primitive is 1-Lipschitz (see primitives.h)
    }
}

namespace {
Bounds3 transformBounds(const Bounds3& b, const auto& map) {
    if (b.empty()) return b;
    if (!b.finite()) return Bounds3::everything();
    Bounds3 out;
    for (int c = 0; c < 8; ++c) {
        Vec3 corner((c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y,
                    (c & 4) ? b.hi.z : b.lo.z);
        out.include(map(corner));
    }
    return out;
}
}  // namespace

bool dominatesBounds(const Node& n) {
    auto child = [&](size_t i) { return dominatesBounds(*n.children[i]); };
    switch (n.kind) {
#define SDFT_PRIMITIVE_DOMINATES(Kind, name, eval, bounds, convex, dominates) \
    case NodeKind::Kind:                                                      \
        return dominates;
        SDFT_PRIMITIVES(SDFT_PRIMITIVE_DOMINATES)
#undef SDFT_PRIMITIVE_DOMINATES
        case NodeKind::Union:
        case NodeKind::SmoothUnion: {  // the smooth union's bounds are grown by k >= the blend's
                                       // dip
            for (size_t i = 0; i < n.children.size(); ++i)
                if (!child(i)) return false;
            return true;
        }
        case NodeKind::Difference:
        case NodeKind::SmoothDifference:  // max(a, -b) >= a, and the bounds are a's
        case NodeKind::Translate:
        case NodeKind::Rotate:
        case NodeKind::Repeat:
            return child(0);
        case NodeKind::Scale:
            return n.params[0] == n.params[1] && n.params[1] == n.params[2] && child(0);
        default:
            return false;  // bounds (ellipsoid, polyhedra), intersections, morph, displace
    }
}

float displaceScale(const Node& n) {
    float child = lipschitzBound(*n.children[0]);
    float added =
        noise::fbmLipschitz(n.params[0], n.params[1], static_cast<int>(n.params[2]), n.params[3]);
    return child / (child + added);
}

std::vector<NodePtr> topLevelObjects(const NodePtr& root) {
    if (!root) return {};
    if (root->kind == NodeKind::Union) return root->children;
    return {root};
}

Bounds3 nodeBounds(const Node& n) {
    const auto& k = n.params;
    auto child = [&](size_t i) { return nodeBounds(*n.children[i]); };
    switch (n.kind) {
#define SDFT_PRIMITIVE_BOUNDS(Kind, name, eval, bounds, ...) \
    case NodeKind::Kind:                                     \
        return bounds(k.data());
        SDFT_PRIMITIVES(SDFT_PRIMITIVE_BOUNDS)
#undef SDFT_PRIMITIVE_BOUNDS
        case NodeKind::Grid:  // unknown until a pending grid is loaded
            return n.grid ? n.grid->shape().bounds() : Bounds3::everything();
        case NodeKind::Union:
        case NodeKind::Morph: {
            Bounds3 b;
            for (size_t i = 0; i < n.children.size(); ++i) b = unite(b, child(i));
            return b;
        }
        case NodeKind::SmoothUnion:
            // The blend lowers the value by at most k/4, which can grow the surface near the seam.
            return unite(child(0), child(1)).expanded(k[0]);
        case NodeKind::Intersection: {
            Bounds3 b = Bounds3::everything();
            for (size_t i = 0; i < n.children.size(); ++i) b = intersect(b, child(i));
            return b;
        }
        case NodeKind::SmoothIntersection:
            return intersect(child(0), child(1));
        case NodeKind::Difference:
        case NodeKind::SmoothDifference:
            return child(0);
        case NodeKind::Complement:
            return Bounds3::everything();
        case NodeKind::Translate: {
            Vec3 t(k[0], k[1], k[2]);
            Bounds3 b = child(0);
            return b.empty() ? b : Bounds3{b.lo + t, b.hi + t};
        }
        case NodeKind::Rotate: {
            Mat3 r;
            for (int i = 0; i < 9; ++i) r.m[i / 3][i % 3] = k[i];
            return transformBounds(child(0), [&](Vec3 p) { return r * p; });
        }
        case NodeKind::Scale: {
            Vec3 s(k[0], k[1], k[2]);
            Bounds3 b = child(0);
            return b.empty() ? b : Bounds3{b.lo * s, b.hi * s};
        }
        case NodeKind::Repeat: {
            Bounds3 b = child(0);
            Vec3 reach = Vec3(k[0], k[1], k[2]) * Vec3(k[3], k[4], k[5]);
            return b.empty() ? b : Bounds3{b.lo - reach, b.hi + reach};
        }
        case NodeKind::Displace: {
            // |displacement| <= amplitude * max|fbm|; a margin of 2x covers children whose value is
            // a bound rather than the exact distance.
            float a = k[0] * noise::fbmMaxAbs(static_cast<int>(k[2]), k[3]);
            return child(0).expanded(2 * a);
        }
    }
    return Bounds3::everything();
}

float evalTree(const Node& n, Vec3 p) {
    const float* k = n.params.data();
    auto child = [&](size_t i, Vec3 q) { return evalTree(*n.children[i], q); };
    float h;
    switch (n.kind) {
#define SDFT_PRIMITIVE_TREE(Kind, name, eval, ...) \
    case NodeKind::Kind:                           \
        return eval(p, k);
        SDFT_PRIMITIVES(SDFT_PRIMITIVE_TREE)
#undef SDFT_PRIMITIVE_TREE
        case NodeKind::Grid:
            SDFT_CHECK(n.grid != nullptr);
            return gridDistanceBound(n.grid->view(), p);
        case NodeKind::Union: {
            float v = child(0, p);
            for (size_t i = 1; i < n.children.size(); ++i) v = minf(v, child(i, p));
            return v;
        }
        case NodeKind::Intersection: {
            float v = child(0, p);
            for (size_t i = 1; i < n.children.size(); ++i) v = maxf(v, child(i, p));
            return v;
        }
        case NodeKind::Difference:
            return maxf(child(0, p), -child(1, p));
        case NodeKind::Complement:
            return -child(0, p);
        case NodeKind::SmoothUnion:
            return ops::smoothMin(child(0, p), child(1, p), k[0], h);
        case NodeKind::SmoothIntersection:
            return ops::smoothMax(child(0, p), child(1, p), k[0], h);
        case NodeKind::SmoothDifference:
            return ops::smoothMax(child(0, p), -child(1, p), k[0], h);
        case NodeKind::Morph:
            return (1 - k[0]) * child(0, p) + k[0] * child(1, p);
        case NodeKind::Translate:
            return child(0, p - Vec3(k[0], k[1], k[2]));
        case NodeKind::Rotate: {
            Mat3 r;
            for (int i = 0; i < 9; ++i) r.m[i / 3][i % 3] = k[i];
            return child(0, r.transposed() * p);
        }
        case NodeKind::Scale: {
            Vec3 s(k[0], k[1], k[2]);
            return child(0, p / s) * minComponent(s);
        }
        case NodeKind::Repeat: {
            const Vec3 q = xform::repeatPoint(p, k);
            float v = child(0, q);
            if (!dominatesBounds(*n.children[0])) {  // as the tape does (transforms.h)
                const Bounds3 b = nodeBounds(*n.children[0]);
                const float box[6] = {b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z};
                v = xform::floorByBounds(v, q, box);
            }
            return minf(v, xform::repeatNeighbourBound(p, k));
        }
        case NodeKind::Displace:
            return (child(0, p) + k[0] * noise::fbm(p * k[1], static_cast<int>(k[2]), k[3])) *
                   displaceScale(n);
    }
    return 0;
}

bool hasPendingAssets(const Node& n) {
    if (n.kind == NodeKind::Grid) return !n.grid;
    for (const NodePtr& c : n.children)
        if (hasPendingAssets(*c)) return true;
    return false;
}

bool isConvex(const Node& n) {
    switch (n.kind) {
#define SDFT_PRIMITIVE_CONVEX(Kind, name, eval, bounds, convex, ...) \
    case NodeKind::Kind:                                             \
        return convex;
        SDFT_PRIMITIVES(SDFT_PRIMITIVE_CONVEX)
#undef SDFT_PRIMITIVE_CONVEX
        case NodeKind::Intersection:
        case NodeKind::Translate:
        case NodeKind::Rotate:
        case NodeKind::Scale:
            for (const NodePtr& c : n.children)
                if (!isConvex(*c)) return false;
            return !n.children.empty();
        default:
            return false;
    }
}

}  // namespace sdft
