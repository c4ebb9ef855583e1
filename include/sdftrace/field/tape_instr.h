// The tape's instruction set (field/tape.h compiles a tree to it; field/tape_view.h evaluates it):
// one instruction per node, registers holding points (for domain transforms) or scalars
// (distances). Plain data, the same on the CPU and a device.
#pragma once

#include <cstdint>

#include "sdftrace/field/primitive_table.h"

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
    Copy,           // out = a (a pruned fold's first kept operand, field/tape_prune.h)
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
    // least the running minimum in scalar b plus the margin k[6] away from point a; jump to
    // `jump`. See decision 0002.
    CullIfFar,
    // control: evaluate the whole tape's instructions k .. jump - 1 here, then go on (a pruned
    // tape's stretch kept as the whole tape has it, field/tape_prune.h; never in a whole tape).
    Run,
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

}  // namespace sdft
