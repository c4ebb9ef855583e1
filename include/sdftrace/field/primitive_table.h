// The analytic primitives, one row each: everything the field module needs to know of a primitive
// besides its parameter layout (its factory in node.h). NodeKind and the tape's Op list the
// primitives from this table, and the switches over them (names, bounds, convexity, bounds
// dominance, tree and tape evaluation, scalar and batch) are generated from it; the scene module
// pairs every row with a parse function by name (scene/parse_primitive.cpp, a compile error when
// one is missing). Adding a primitive: an evaluator and a bounds function in primitives.h, a
// factory in node.h, a row here, a parse function.
//
//   X(Kind, scene-file name, evaluator, bounds, convex, dominates bounds)
//
// - convex: the solid is convex (Keinert et al. 2014, §3.5 traces refracted rays inside such
//   objects back from their box). The plane is convex but unbounded, so it is not listed as such.
// - dominates bounds: the value is at least the distance to the bounds outside them (exact
//   distances; blobs by their max with the support spheres), which bounds culling of smooth unions
//   relies on (decision 0002). Distance bounds (ellipsoid, polyhedra) are not.
// Every primitive is 1-Lipschitz.
#pragma once

#include "sdftrace/field/primitives.h"

#define SDFT_PRIMITIVES(X)                                                                         \
    X(Sphere, "sphere", ::sdft::prim::sphere, ::sdft::prim::sphereBounds, true, true)              \
    X(Box, "box", ::sdft::prim::box, ::sdft::prim::boxBounds, true, true)                          \
    X(RoundBox, "round_box", ::sdft::prim::roundBox, ::sdft::prim::roundBoxBounds, true, true)     \
    X(Torus, "torus", ::sdft::prim::torus, ::sdft::prim::torusBounds, false, true)                 \
    X(Capsule, "capsule", ::sdft::prim::capsule, ::sdft::prim::capsuleBounds, true, true)          \
    X(Cylinder, "cylinder", ::sdft::prim::cylinder, ::sdft::prim::cylinderBounds, true, true)      \
    X(Cone, "cone", ::sdft::prim::cone, ::sdft::prim::coneBounds, true, true)                      \
    X(Plane, "plane", ::sdft::prim::plane, ::sdft::prim::planeBounds, false, false)                \
    X(Ellipsoid, "ellipsoid", ::sdft::prim::ellipsoid, ::sdft::prim::ellipsoidBounds, true, false) \
    X(Octahedron, "octahedron", ::sdft::prim::octahedron, ::sdft::prim::octahedronBounds, true,    \
      false)                                                                                       \
    X(Dodecahedron, "dodecahedron", ::sdft::prim::dodecahedron, ::sdft::prim::dodecahedronBounds,  \
      true, false)                                                                                 \
    X(Blobs, "blobs", ::sdft::prim::blobs, ::sdft::prim::blobsBounds, false, true)
