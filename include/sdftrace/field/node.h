// The analytic field as a tree of nodes: primitives, CSG operators, transforms, displacement,
// morph. Built by the scene parser (or by code); compiled to a flat Tape for evaluation
// (docs/design.md: tree -> tape -> batch evaluators). evalTree() is the plain recursive reference
// the tests compare the tape against.
#pragma once

#include <memory>
#include <vector>

#include "sdftrace/field/primitive_table.h"
#include "sdftrace/math/ray.h"
#include "sdftrace/math/vec.h"

namespace sdft {
class Grid;
}

namespace sdft {

enum class NodeKind {
// primitives (primitive_table.h), then grids
#define SDFT_PRIMITIVE_KIND(Kind, ...) Kind,
    SDFT_PRIMITIVES(SDFT_PRIMITIVE_KIND)
#undef SDFT_PRIMITIVE_KIND
        Grid,  // a sampled field (dense or sparse block grid), trilinear
    // operators
    Union,
    Intersection,
    Difference,
    Complement,
    SmoothUnion,
    SmoothIntersection,
    SmoothDifference,
    Morph,
    // domain transforms (one child)
    Translate,
    Rotate,
    Scale,
    Repeat,
    // value modifier (one child)
    Displace,
};

struct Node;
using NodePtr = std::shared_ptr<const Node>;

struct Node {
    NodeKind kind;
    // Kind-specific parameters, in the layout documented at each factory below.
    std::vector<float> params;
    std::vector<NodePtr> children;
    // Index into the scene's material table; -1 inherits the parent's.
    int material = -1;
    // NodeKind::Grid: the samples (shared, immutable).
    std::shared_ptr<const Grid> grid;
    // NodeKind::Grid in a scene that is described but not yet prepared (scene/prepare_scene.h):
    // the index of the asset request that will supply `grid`, which is null until then.
    int asset = -1;
};

bool isPrimitive(NodeKind kind);
const char* nodeKindName(NodeKind kind);

// Factories. Parameters are validated by the scene parser, not here (SDFT_CHECK guards invariants).
namespace node {
NodePtr sphere(float radius);
NodePtr box(Vec3 halfSize);
NodePtr roundBox(Vec3 halfSize, float radius);
NodePtr torus(float majorRadius, float minorRadius);
NodePtr capsule(Vec3 a, Vec3 b, float radius);
NodePtr cylinder(float radius, float halfHeight);
NodePtr cone(float radius, float height);
NodePtr plane(Vec3 normal, float offset);
NodePtr ellipsoid(Vec3 radii);
NodePtr octahedron(float size);
NodePtr dodecahedron(float inradius);
struct Blob {
    Vec3 center;
    float radius;    // support radius R
    float strength;  // s
};
NodePtr blobs(const std::vector<Blob>& blobs, float threshold);
// A sampled field; its value is the trilinear reconstruction divided by the grid's Lipschitz bound.
NodePtr grid(std::shared_ptr<const Grid> grid);
// A grid still to be loaded or baked: asset request `index` of its scene.
NodePtr gridAsset(int index);

NodePtr unite(std::vector<NodePtr> children);
NodePtr intersect(std::vector<NodePtr> children);
NodePtr subtract(NodePtr a, NodePtr b);
NodePtr complement(NodePtr a);
NodePtr smoothUnion(NodePtr a, NodePtr b, float k);
NodePtr smoothIntersection(NodePtr a, NodePtr b, float k);
NodePtr smoothDifference(NodePtr a, NodePtr b, float k);
NodePtr morph(NodePtr a, NodePtr b, float weight);

NodePtr translate(NodePtr child, Vec3 offset);
NodePtr rotate(NodePtr child, const Mat3& rotation);
NodePtr scale(NodePtr child, Vec3 factors);
// Repeats the child on a lattice with spacing `cell`, `count` copies on each side of the original
// along each axis (0 = no repetition on that axis).
NodePtr repeat(NodePtr child, Vec3 cell, Vec3 count);
NodePtr displace(NodePtr child, float amplitude, float frequency, int octaves, float gain);

NodePtr withMaterial(NodePtr n, int material);
}  // namespace node

// Lipschitz bound of the node's value (Liktor 2008, §2.2).
float lipschitzBound(const Node& n);
// f + A fbm(p) is (L_f + L_noise)-Lipschitz; the displace node multiplies it by
// L_f / (L_f + L_noise) so it keeps its child's bound and slows only rays near the displaced
// object, not the whole scene.
float displaceScale(const Node& n);
// Axis-aligned box containing the node's surface and interior (may be infinite).
Bounds3 nodeBounds(const Node& n);
// A scene's top-level objects: the children of its root union, or the root alone.
std::vector<NodePtr> topLevelObjects(const NodePtr& root);
// True when the node's value is at least the distance to nodeBounds() at every point outside those
// bounds (exact-distance primitives, blobs, rigid or uniformly scaled transforms, unions and
// repetitions of such). Bounds culling of smooth unions relies on it (decision 0002).
bool dominatesBounds(const Node& n);
// Whether the node's solid is convex: convex primitives, their intersections and transforms
// (Keinert et al. 2014, §3.5 traces rays inside such objects back from their bounds).
bool isConvex(const Node& node);
// Whether the tree holds grids not loaded yet (node::gridAsset).
bool hasPendingAssets(const Node& n);
// Recursive reference evaluation of the tree (slow; the tests' ground truth for the tape).
float evalTree(const Node& n, Vec3 p);

}  // namespace sdft
