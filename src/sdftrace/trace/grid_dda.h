// The two-level DDA of Jamriška 2010 (§4) and its parts, as header code a device thread runs as
// the CPU does (docs/gpu.md): the Amanatides & Woo walker, the cell intersection of §4.2
// (midpoint or false position), the block walk with bit masks (§4.1), empty-space skipping, the
// volumetric-occluder shadow traversal of §7 and the three gradient estimators of §5. The CPU's
// entry points (trace/grid_tracer.h) build these for AVX2 and the baseline.
#pragma once

#include <cmath>
#include <cstdint>

#include "sdftrace/core/macros.h"
#include "sdftrace/field/block_table.h"
#include "sdftrace/field/grid.h"
#include "sdftrace/math/ray.h"
#include "sdftrace/trace/grid_tracer.h"

namespace sdft::grid_dda {

SDFT_HOST_DEVICE inline int mini(int a, int b) { return b < a ? b : a; }
SDFT_HOST_DEVICE inline int maxi(int a, int b) { return a < b ? b : a; }
SDFT_HOST_DEVICE inline int clampi(int v, int lo, int hi) {
    return v < lo ? lo : (hi < v ? hi : v);
}

// Amanatides & Woo 3D-DDA over a lattice of cubes of edge `size` (grid units) whose indices lie in
// [lo, hi] per axis, starting at parameter t (ray in grid units: p(t) = o + t d).
// Each boundary's parameter is computed from its index, not accumulated, so a traversal that
// restarts further along the ray (empty-space skipping) meets exactly the same values.
struct Dda {
    int idx[3], step[3], lo[3], hi[3];
    float tNext[3];
    float t;
    float org[3], inv[3], size;

    // invD: 1 / d per axis (inf where d is 0), computed once per ray.
    SDFT_HOST_DEVICE void init(const Vec3& o, const Vec3& d, const float invD[3], float tStart,
                               float size_, const int lo_[3], const int hi_[3]) {
        t = tStart;
        size = size_;
        Vec3 p = o + d * tStart;
        for (int a = 0; a < 3; ++a) {
            org[a] = o[a];
            inv[a] = invD[a];
            lo[a] = lo_[a];
            hi[a] = hi_[a];
            int i = static_cast<int>(std::floor(p[a] / size));
            idx[a] = clampi(i, lo[a], hi[a]);
            if (d[a] > 0) {
                step[a] = 1;
                tNext[a] = ((idx[a] + 1) * size - o[a]) * invD[a];
            } else if (d[a] < 0) {
                step[a] = -1;
                tNext[a] = (idx[a] * size - o[a]) * invD[a];
            } else {
                step[a] = 0;
                tNext[a] = kInfinity;
            }
        }
    }
    // Parameter where the current cube is left.
    SDFT_HOST_DEVICE float exit() const { return minf(minf(tNext[0], tNext[1]), tNext[2]); }
    // Moves to the next cube; false when it leaves [lo, hi]. Each axis with constant indices, so
    // that the compiler can keep the whole walker in registers.
    SDFT_HOST_DEVICE bool advance() {
        if (tNext[0] < tNext[1] ? tNext[0] < tNext[2] : false) return advanceAxis<0>();
        if (!(tNext[0] < tNext[1]) && tNext[1] < tNext[2]) return advanceAxis<1>();
        return advanceAxis<2>();
    }
    template <int a>
    SDFT_HOST_DEVICE bool advanceAxis() {
        t = tNext[a];
        idx[a] += step[a];
        tNext[a] = ((idx[a] + (step[a] > 0)) * size - org[a]) * inv[a];
        return idx[a] >= lo[a] && idx[a] <= hi[a];
    }
};

// The ray in grid units: origin and direction divided by the voxel size, so t is shared with world
// space (t_world = t_grid because the direction keeps unit length in world units / voxel units).
struct GridRay {
    Vec3 o, d;
};

SDFT_HOST_DEVICE inline float valueAt(const GridView& g, const GridRay& r, float t, int ci, int cj,
                                      int ck, const float c[8]) {
    Vec3 p = r.o + r.d * t;
    float u = clampf(p.x - ci, 0.f, 1.f), v = clampf(p.y - cj, 0.f, 1.f),
          w = clampf(p.z - ck, 0.f, 1.f);
    return trilinear(c, u, v, w);
}

// Jamriška §5, the analytic estimator: the derivatives of the trilinear filter of a cell's corners
// c[i + 2 j + 4 k] at local coordinates (u, v, w), in grid units.
SDFT_HOST_DEVICE inline Vec3 trilinearGradient(const float c[8], float u, float v, float w) {
    auto lerp1 = [](float a, float b, float t) { return a + (b - a) * t; };
    return {lerp1(lerp1(c[1] - c[0], c[3] - c[2], v), lerp1(c[5] - c[4], c[7] - c[6], v), w),
            lerp1(lerp1(c[2] - c[0], c[3] - c[1], u), lerp1(c[6] - c[4], c[7] - c[5], u), w),
            lerp1(lerp1(c[4] - c[0], c[5] - c[1], u), lerp1(c[6] - c[2], c[7] - c[3], u), v)};
}

// trilinearGradient at the ray's point at t, in cell (ci, cj, ck).
SDFT_HOST_DEVICE inline Vec3 gradientAt(const GridRay& r, float t, int ci, int cj, int ck,
                                        const float c[8]) {
    const Vec3 p = r.o + r.d * t;
    return trilinearGradient(c, clampf(p.x - ci, 0.f, 1.f), clampf(p.y - cj, 0.f, 1.f),
                             clampf(p.z - ck, 0.f, 1.f));
}

// Jamriška §4.2 inside one surface cell on [tIn, tOut]: true and the hit parameter if the
// reconstruction changes sign (relative to `sign`, +1 for rays starting outside).
// `c` holds the cell's 8 corner samples.
SDFT_HOST_DEVICE inline bool intersectCell(const GridView& g, const GridRay& r, int ci, int cj,
                                           int ck, const float c[8], float tIn, float tOut,
                                           float sign, const GridTraceOptions& o,
                                           GridTraceResult& res, float& tHit) {
    res.intersectionTests++;
    if (o.cellMethod == CellIntersection::Midpoint) {
        tHit = 0.5f * (tIn + tOut);  // assumes every surface cell is hit (fast, shows artifacts)
        res.gradient = gradientAt(r, tHit, ci, cj, ck, c);
        return true;
    }
    float fIn = sign * valueAt(g, r, tIn, ci, cj, ck, c);
    float fOut = sign * valueAt(g, r, tOut, ci, cj, ck, c);
    res.interpolations += 2;
    if (fIn > 0 && fOut > 0) return false;
    if (fIn <= 0) {  // already at or behind the surface where the cell is entered
        tHit = tIn;
        res.gradient = gradientAt(r, tHit, ci, cj, ck, c);
        return true;
    }
    float t1 = tIn, f1 = fIn, t2 = tOut, f2 = fOut;
    tHit = t1 + (t2 - t1) * f1 / (f1 - f2);
    for (int i = 1; i < o.falsiIters; ++i) {
        float f = sign * valueAt(g, r, tHit, ci, cj, ck, c);
        res.interpolations++;
        if (f > 0) {
            t1 = tHit;
            f1 = f;
        } else {
            t2 = tHit;
            f2 = f;
        }
        if (f1 == f2) break;
        tHit = t1 + (t2 - t1) * f1 / (f1 - f2);
    }
    res.gradient = gradientAt(r, tHit, ci, cj, ck, c);
    return true;
}

struct Setup {
    GridRay r;
    float invD[3];
    float t0, t1;
    float sign;
    int blockLo[3], blockHi[3];
    int B;
};

// gridSignAt (grid_tracer.h).
SDFT_HOST_DEVICE inline float signAt(const GridView& g, Vec3 p) {
    const Vec3 q = (p - g.shape.origin) / g.shape.voxelSize;
    for (int a = 0; a < 3; ++a)
        if (!(q[a] >= 0 && q[a] <= static_cast<float>(g.shape.cells[a]))) return 1.0f;
    return g.interpolate(p) >= 0 ? 1.0f : -1.0f;
}

// The sign a ray starts with at t0 (traceGridRay): +1 for a ray clipped to the grid's box (it
// starts on the boundary, outside the solid: a surface cut by the box is found at the entry cell),
// else the caller's `known` sign, else the first sample's.
SDFT_HOST_DEVICE inline float raySign(const GridView& g, const Ray& ray, float t0, bool clipped,
                                      float known) {
    if (clipped) return 1.0f;
    if (known != 0) return known;
    return g.interpolate(ray.at(t0)) >= 0 ? 1.0f : -1.0f;
}

// Clips the ray to the grid and prepares both traversal levels. False if the grid is missed.
// startSign: the field's sign at tMin where the caller knows it (traceGridRay), 0 to look it up.
SDFT_HOST_DEVICE inline bool setup(const GridView& g, const Ray& ray, float tMin, float tMax,
                                   Setup& s, float startSign = 0) {
    const float h = g.shape.voxelSize;
    s.r = {(ray.origin - g.shape.origin) / h, ray.direction / h};
    for (int a = 0; a < 3; ++a) s.invD[a] = s.r.d[a] != 0 ? 1.0f / s.r.d[a] : kInfinity;
    Bounds3 box{Vec3(0.0f), Vec3(g.shape.cells[0], g.shape.cells[1], g.shape.cells[2])};
    if (!intersectBounds(box, Ray{s.r.o, s.r.d}, tMin, tMax, s.t0, s.t1)) return false;
    // A dense grid is one block of the whole grid.
    s.B = g.kind == GridKind::Sparse
              ? g.blockSize
              : maxi(maxi(g.shape.cells[0], g.shape.cells[1]), g.shape.cells[2]);
    for (int a = 0; a < 3; ++a) {
        s.blockLo[a] = 0;
        s.blockHi[a] = g.kind == GridKind::Sparse ? g.blocks[a] - 1 : 0;
    }
    s.sign = raySign(g, ray, s.t0, s.t0 > tMin, startSign);
    return true;
}

SDFT_HOST_DEVICE inline BlockFlag blockFlag(const GridView& g, const int b[3]) {
    if (g.kind == GridKind::Dense) return BlockFlag::Surface;
    return static_cast<BlockFlag>(g.flags[g.blockSlot(b[0], b[1], b[2])]);
}

// traverseBlock's cell walk for a sparse block with its bit mask (Jamriška §4.1, the common
// case): the Dda's start, then its state in scalars so that it stays in registers, and the mask
// bit (also the cell's first corner among the block's own samples) stepped along with the cell.
// The same cells, boundaries and tests as the Dda (the same expressions and tie-breaking), so the
// same hits and t. B is a template parameter: the bit steps and the corner reads are constants.
template <int B>
SDFT_HOST_DEVICE inline bool walkMaskedCells(const GridView& g, const Setup& s, const int lo[3],
                                             const int hi[3], const uint64_t* mask, int32_t data,
                                             float tEnter, float tExit, const GridTraceOptions& o,
                                             GridTraceResult& res, float& tHit) {
    const float* blockSamples = g.blockSamples;
    const int32_t* blockNeighbors = g.blockNeighbors;
    Dda start;
    start.init(s.r.o, s.r.d, s.invD, tEnter, 1.0f, lo, hi);
    int ix = start.idx[0], iy = start.idx[1], iz = start.idx[2];
    const int sx0 = start.step[0], sy0 = start.step[1], sz0 = start.step[2];
    float tx = start.tNext[0], ty = start.tNext[1], tz = start.tNext[2];
    const float ox = s.r.o[0], oy = s.r.o[1], oz = s.r.o[2];
    const float vx = s.invD[0], vy = s.invD[1], vz = s.invD[2];
    // The cell's bit is also its first corner's index among the block's B^3 own samples.
    int bit = ((iz - lo[2]) * B + (iy - lo[1])) * B + (ix - lo[0]);
    float t = tEnter;
    int steps = 0;
    bool hit = false;
    for (;;) {
        ++steps;
        const float tOut = minf(minf(minf(tx, ty), tz), tExit);
        if ((mask[bit >> 6] >> (bit & 63)) & 1) {
            float c[8];
            blockCellCornersOf<B>(blockSamples, blockNeighbors, data, ix - lo[0], iy - lo[1],
                                  iz - lo[2], c);
            if (intersectCell(g, s.r, ix, iy, iz, c, t, tOut, s.sign, o, res, tHit)) {
                hit = true;
                break;
            }
        }
        if (tOut >= tExit) break;
        if (tx < ty ? tx < tz : false) {
            t = tx;
            ix += sx0;
            if (ix < lo[0] || ix > hi[0]) break;
            bit += sx0;
            tx = ((ix + (sx0 > 0)) * 1.0f - ox) * vx;
        } else if (!(tx < ty) && ty < tz) {
            t = ty;
            iy += sy0;
            if (iy < lo[1] || iy > hi[1]) break;
            bit += sy0 * B;
            ty = ((iy + (sy0 > 0)) * 1.0f - oy) * vy;
        } else {
            t = tz;
            iz += sz0;
            if (iz < lo[2] || iz > hi[2]) break;
            bit += sz0 * B * B;
            tz = ((iz + (sz0 > 0)) * 1.0f - oz) * vz;
        }
    }
    res.traversalSteps += steps;
    return hit;
}

// The inner loop over the cells of one block on [tEnter, tExit]; true with tHit on a hit. A
// masked sparse block goes to walkMaskedCells; here dense grids and walks without masks, which
// test each cell's corner signs.
SDFT_HOST_DEVICE inline bool traverseBlock(const GridView& g, const Setup& s, const int block[3],
                                           size_t slot, float tEnter, float tExit,
                                           const GridTraceOptions& o, GridTraceResult& res,
                                           float& tHit) {
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
        lo[a] = block[a] * s.B;
        hi[a] = mini(lo[a] + s.B, g.shape.cells[a]) - 1;
    }
    // The block's samples and mask, looked up once (§4.1).
    int32_t data = -1;
    if (g.kind == GridKind::Sparse) {
        data = g.blockData[slot];
        if (o.bitMasks) {
            const uint64_t* mask = g.cellMasks + static_cast<size_t>(data) * g.wordsPerMask();
            return s.B == 8
                       ? walkMaskedCells<8>(g, s, lo, hi, mask, data, tEnter, tExit, o, res, tHit)
                       : walkMaskedCells<4>(g, s, lo, hi, mask, data, tEnter, tExit, o, res, tHit);
        }
    }
    Dda cells;
    cells.init(s.r.o, s.r.d, s.invD, tEnter, 1.0f, lo, hi);
    // Counted locally: res may alias the grid's buffers, a store per step otherwise.
    int steps = 0;
    for (;;) {
        ++steps;
        float tIn = cells.t, tOut = minf(cells.exit(), tExit);
        float c[8];
        if (data >= 0) {
            g.blockCellCorners(data, cells.idx[0] - lo[0], cells.idx[1] - lo[1],
                               cells.idx[2] - lo[2], c);
        } else {
            g.cellCorners(cells.idx[0], cells.idx[1], cells.idx[2], c);
        }
        if (cornersChangeSign(c) && intersectCell(g, s.r, cells.idx[0], cells.idx[1], cells.idx[2],
                                                  c, tIn, tOut, s.sign, o, res, tHit)) {
            res.traversalSteps += steps;
            return true;
        }
        if (tOut >= tExit || !cells.advance()) {
            res.traversalSteps += steps;
            return false;
        }
    }
}

// Empty-space skipping (not in the papers: Cohen & Sheffer's proximity clouds on Jamriška's block
// level, §4.1): no block (tile) within r of the walk's current one holds a sign-changing cell, so
// the walk may restart where the ray leaves that cube of blocks (tiles, shift = kTileShift); only
// cells that are never tested are skipped, so the hits are the plain traversal's.
enum class Skip { LeftGrid, Restarted, CubeEndsHere };
SDFT_HOST_DEVICE inline Skip skipCube(const Setup& s, Dda& blocks, int r, int shift, float tExit) {
    const float unit = static_cast<float>(s.B) * static_cast<float>(1 << shift);
    float tCube = kInfinity;
    int c[3];  // the cube's centre block or tile
    for (int a = 0; a < 3; ++a) {
        c[a] = blocks.idx[a] >> shift;
        if (s.r.d[a] > 0)
            tCube = minf(tCube, ((c[a] + r + 1) * unit - s.r.o[a]) * s.invD[a]);
        else if (s.r.d[a] < 0)
            tCube = minf(tCube, ((c[a] - r) * unit - s.r.o[a]) * s.invD[a]);
    }
    if (tCube >= s.t1) return Skip::LeftGrid;
    if (tCube <= tExit) return Skip::CubeEndsHere;
    blocks.init(s.r.o, s.r.d, s.invD, tCube, static_cast<float>(s.B), s.blockLo, s.blockHi);
    // Rounding can put the point at tCube back inside the cube (leaving through an edge, two
    // faces' crossings round apart), and the same cube would be skipped to the same point
    // forever: step out of it block by block (it holds no sign-changing cell).
    auto inCube = [&] {
        for (int a = 0; a < 3; ++a) {
            const int d = (blocks.idx[a] >> shift) - c[a];
            if (d < -r || d > r) return false;
        }
        return true;
    };
    while (inCube())
        if (!blocks.advance()) return Skip::LeftGrid;
    return blocks.t < s.t1 ? Skip::Restarted : Skip::LeftGrid;
}

// The outer loop (§4.1): blocks along the ray from `blocks` on; blocks without a sign-changing
// cell are skipped (by whole cubes where the skip tables allow), the others walked cell by cell.
// Fills res.hit and res.t on a hit.
SDFT_HOST_DEVICE inline void traverseBlocks(const GridView& g, const Setup& s, Dda blocks,
                                            const GridTraceOptions& o, GridTraceResult& res) {
    for (;;) {
        res.traversalSteps++;
        const float tEnter = blocks.t, tExit = minf(blocks.exit(), s.t1);
        size_t slot = 0;       // the block's entry in the paged tables (sparse)
        int r = 0, shift = 0;  // a cube to skip: radius and log2 of its unit, in blocks
        bool walk = g.kind == GridKind::Dense;
        if (!walk) {
            const size_t tile = g.tileIndex(blocks.idx[0], blocks.idx[1], blocks.idx[2]);
            if (g.tileSkip && g.tileSkip[tile] > 0) {
                r = g.tileSkip[tile] - 1;
                shift = kTileShift;
            } else {
                slot = static_cast<size_t>(g.tilePage[tile]) * kPageEntries +
                       pageLocal(blocks.idx[0], blocks.idx[1], blocks.idx[2]);
                walk = g.mayHoldHit(slot);
                if (!walk && g.blockSkip) r = g.blockSkip[slot] - 1;
            }
        }
        float tHit;
        if (walk && traverseBlock(g, s, blocks.idx, slot, tEnter, tExit, o, res, tHit)) {
            res.hit = true;
            res.t = tHit;
            return;
        }
        if (r > 0 || shift > 0) {
            const Skip skip = skipCube(s, blocks, r, shift, tExit);
            if (skip == Skip::LeftGrid) return;
            if (skip == Skip::Restarted) continue;
        }
        if (tExit >= s.t1 || !blocks.advance()) return;
    }
}

// traceGridRay (grid_tracer.h).
SDFT_HOST_DEVICE inline GridTraceResult traceRay(const GridView& g, const Ray& ray, float tMin,
                                                 float tMax, const GridTraceOptions& o,
                                                 float startSign = 0) {
    GridTraceResult res;
    Setup s;
    if (!setup(g, ray, tMin, tMax, s, startSign)) return res;
    Dda blocks;
    blocks.init(s.r.o, s.r.d, s.invD, s.t0, static_cast<float>(s.B), s.blockLo, s.blockHi);
    traverseBlocks(g, s, blocks, o, res);
    return res;
}

// traceGridShadow (grid_tracer.h).
SDFT_HOST_DEVICE inline GridTraceResult traceShadow(const GridView& g, const Ray& ray, float tMin,
                                                    float tMax, const GridTraceOptions& o,
                                                    int threshold) {
    if (threshold <= 0 || g.kind != GridKind::Sparse) return traceRay(g, ray, tMin, tMax, o);
    GridTraceResult res;
    Setup s;
    if (!setup(g, ray, tMin, tMax, s)) return res;
    Dda blocks;
    blocks.init(s.r.o, s.r.d, s.invD, s.t0, static_cast<float>(s.B), s.blockLo, s.blockHi);
    // Jamriška §7: coarse blocks only, hoping for an inside block (a volumetric occluder).
    bool sawSurface = false;
    Dda restart{};
    int sinceSurface = 0;
    for (;;) {
        res.traversalSteps++;
        BlockFlag f = blockFlag(g, blocks.idx);
        if (f == BlockFlag::Inside && s.sign > 0) {
            res.hit = true;
            res.t = blocks.t;
            return res;
        }
        if (f == BlockFlag::Surface && !sawSurface) {
            sawSurface = true;
            restart = blocks;
        }
        if (sawSurface && ++sinceSurface > threshold) break;
        float tExit = minf(blocks.exit(), s.t1);
        if (tExit >= s.t1 || !blocks.advance()) {
            if (!sawSurface) return res;
            break;
        }
    }
    // Restart the full traversal from the first surface block.
    traverseBlocks(g, s, restart, o, res);
    return res;
}

// gridNormal (grid_tracer.h): Jamriška §5.
SDFT_HOST_DEVICE inline Vec3 gradientNormal(const GridView& g, Vec3 p, GridNormal method) {
    const float h = g.shape.voxelSize;
    Vec3 q = (p - g.shape.origin) / h;
    auto cellOf = [&](float x, int axis) {
        return clampi(static_cast<int>(std::floor(x)), 0, g.shape.cells[axis] - 1);
    };
    Vec3 grad;
    if (method == GridNormal::AnalyticTrilinear) {
        // Derivatives of the trilinear filter inside the cell (8 samples, no interpolation).
        int i = cellOf(q.x, 0), j = cellOf(q.y, 1), k = cellOf(q.z, 2);
        float u = clampf(q.x - i, 0, 1), v = clampf(q.y - j, 0, 1), w = clampf(q.z - k, 0, 1);
        float c[8];
        g.cellCorners(i, j, k, c);
        grad = trilinearGradient(c, u, v, w);
    } else if (method == GridNormal::DifferenceOfInterpolations) {
        // Central differences of interpolated values, one voxel apart.
        for (int a = 0; a < 3; ++a) {
            Vec3 e(0.0f);
            e[a] = 0.5f * h;
            grad[a] = g.interpolate(p + e) - g.interpolate(p - e);
        }
    } else {
        // Central differences at the 8 cell vertices, then trilinear interpolation of them.
        int i = cellOf(q.x, 0), j = cellOf(q.y, 1), k = cellOf(q.z, 2);
        float u = clampf(q.x - i, 0, 1), v = clampf(q.y - j, 0, 1), w = clampf(q.z - k, 0, 1);
        // The 32 vertices the 8 central differences read: nb[z][y][x] for offsets -1..2 from
        // (i, j, k) (index + 1).
        float nb[4][4][4];
        g.gradientStencil(i, j, k, nb);
        Vec3 corner[8];
        for (int n = 0; n < 8; ++n) {
            const int x = 1 + (n & 1), y = 1 + ((n >> 1) & 1), z = 1 + ((n >> 2) & 1);
            corner[n] = {nb[z][y][x + 1] - nb[z][y][x - 1], nb[z][y + 1][x] - nb[z][y - 1][x],
                         nb[z + 1][y][x] - nb[z - 1][y][x]};
        }
        Vec3 c00 = lerp(corner[0], corner[1], u), c10 = lerp(corner[2], corner[3], u);
        Vec3 c01 = lerp(corner[4], corner[5], u), c11 = lerp(corner[6], corner[7], u);
        grad = lerp(lerp(c00, c10, v), lerp(c01, c11, v), w);
    }
    return normalize(grad);
}

// gridHitNormal (grid_tracer.h).
SDFT_HOST_DEVICE inline Vec3 hitNormal(const GridView& g, const GridTraceResult& hit, Vec3 p,
                                       GridNormal method) {
    return method == GridNormal::AnalyticTrilinear ? normalize(hit.gradient)
                                                   : gradientNormal(g, p, method);
}

}  // namespace sdft::grid_dda
