// Jamriška 2010, §6: acceleration of primary rays by min/max buffers. Every surface block's
// bounding sphere is projected to a conservative square on the image; a low-resolution buffer
// keeps, per buffer pixel, the smallest entry (|c - eye| - r) and largest exit (|c - eye| + r)
// distance of the squares covering it. A primary ray then traverses only [tMin, tMax] of its buffer
// pixel, and a pixel no square covers cannot hit the surface (it lies in surface blocks only).
// The per-block pieces (which blocks, their squares) and the lookup are header functions: the
// CPU's build (TBB over tiles) and the GPU's (gpu/gpu_minmax.cu, a thread per block with atomic
// min and max) splat the same squares, and a device thread reads its range through MinMaxView.
#pragma once

#include <cmath>
#include <vector>

#include "sdftrace/core/macros.h"
#include "sdftrace/field/grid.h"
#include "sdftrace/math/camera.h"

namespace sdft {

// A buffer's size for a camera: w x h buffer pixels, and buffer pixels per image pixel.
struct MinMaxShape {
    int w = 0, h = 0;
    float scaleX = 1, scaleY = 1;
};
// `resolution` buffer pixels along the image's longer side.
MinMaxShape minMaxShape(const CameraDesc& camera, int resolution);

// A buffer's arrays where a lookup reads them (host or device memory). Plain data.
struct MinMaxView {
    const float* min = nullptr;  // null: no buffer (every range is [0, inf))
    const float* max = nullptr;
    MinMaxShape shape;
    bool everything = false;  // a block reaches the camera plane: no bound
    // The interval a primary ray through image pixel (x, y) must traverse; empty (t0 > t1) if
    // none.
    SDFT_HOST_DEVICE void range(int x, int y, float& t0, float& t1) const {
        if (!min || everything) {
            t0 = 0;
            t1 = kInfinity;
            return;
        }
        const int bx = static_cast<int>((x + 0.5f) * shape.scaleX);
        const int by = static_cast<int>((y + 0.5f) * shape.scaleY);
        const size_t p = static_cast<size_t>(by < shape.h - 1 ? by : shape.h - 1) * shape.w +
                         (bx < shape.w - 1 ? bx : shape.w - 1);
        t0 = fmaxf(0.0f, min[p]);
        t1 = max[p];
    }
};

// What one block's bounding sphere does to a buffer.
struct BlockSquare {
    enum class Kind { Unseen, Everything, Square } kind = Kind::Unseen;
    int x0 = 0, x1 = -1, y0 = 0, y1 = -1;  // the buffer pixels it covers (inclusive)
    float tEnter = 0, tExit = 0;
};

namespace minmax {

// The cells along a splatted block's edge (a dense grid is one block, a cube over its cells).
SDFT_HOST_DEVICE inline int blockCells(const GridView& g) {
    if (g.kind == GridKind::Sparse) return g.blockSize;
    const int* n = g.shape.cells;
    return n[0] > n[1] ? (n[0] > n[2] ? n[0] : n[2]) : (n[1] > n[2] ? n[1] : n[2]);
}

// The bounding-sphere radius of the blocks the buffer splats.
SDFT_HOST_DEVICE inline float blockRadius(const GridView& g) {
    return 0.5f * sqrtf(3.0f) * static_cast<float>(blockCells(g)) * g.shape.voxelSize;
}

// The blocks along each axis (a dense grid: one).
SDFT_HOST_DEVICE inline void blockCounts(const GridView& g, int nb[3]) {
    const bool sparse = g.kind == GridKind::Sparse;
    for (int a = 0; a < 3; ++a) nb[a] = sparse ? g.blocks[a] : 1;
}

// Whether block (i, j, k) is one a ray can hit in (the DDA walks no other: a dense grid's one
// block, a sparse grid's blocks of its own pages that may hold a hit, block_table.h), and its
// centre.
SDFT_HOST_DEVICE inline bool splattedBlock(const GridView& g, int i, int j, int k, Vec3& centre) {
    const float edge = static_cast<float>(blockCells(g)) * g.shape.voxelSize;
    if (g.kind != GridKind::Sparse) {
        centre = g.shape.origin + Vec3(0.5f) * edge;
        return true;
    }
    const int32_t page = g.tilePage[g.tileIndex(i, j, k)];
    if (page < kFirstOwnPage) return false;
    if (!g.mayHoldHit(static_cast<size_t>(page) * kPageEntries + pageLocal(i, j, k))) return false;
    centre =
        g.shape.origin +
        (Vec3(static_cast<float>(i), static_cast<float>(j), static_cast<float>(k)) + Vec3(0.5f)) *
            edge;
    return true;
}

// Jamriška §6: the square the sphere (centre c, radius r) covers on the image, widened
// conservatively, with its entry and exit distances.
SDFT_HOST_DEVICE inline BlockSquare blockSquare(const Camera& cam, Vec3 c, float radius,
                                                const MinMaxShape& s) {
    BlockSquare out;
    const CameraDesc& d = cam.desc();
    const Vec3 rel = c - d.eye;
    const float dist = length(rel), z = dot(rel, cam.forward());
    const float cx = dot(rel, cam.right()), cy = dot(rel, cam.up());
    // A primary ray leaves the eye into the view frustum (|x| <= z tx, |y| <= z ty): a sphere
    // behind the camera plane or outside one of the frustum's four side planes is never met.
    const float ty = cam.tanHalfFov(), tx = ty * static_cast<float>(d.width) / d.height;
    if (z + radius < 0 || (fabsf(cx) - z * tx) > radius * sqrtf(1 + tx * tx) ||
        (fabsf(cy) - z * ty) > radius * sqrtf(1 + ty * ty))
        return out;
    if (z - radius <= 1e-6f * dist || dist <= radius) {
        out.kind = BlockSquare::Kind::Everything;  // the sphere reaches the camera plane
        return out;
    }
    // Centre in image pixels and a conservative half-width per axis. A sphere point q = c + e
    // (|e| <= r) projects to q_x / q_z; |q_x/q_z - c_x/c_z| = |e_x c_z - c_x e_z| / (q_z c_z)
    // <= r (c_z + |c_x|) / ((c_z - r) c_z).
    float px = 0, py = 0;  // z > r > 0: the centre projects
    cam.project(c, px, py);
    const float pixelsPerUnit = 0.5f * d.height / cam.tanHalfFov();  // image plane to pixels
    const float halfX = radius * (z + fabsf(cx)) / ((z - radius) * z) * pixelsPerUnit;
    const float halfY = radius * (z + fabsf(cy)) / ((z - radius) * z) * pixelsPerUnit;
    const int x0 = static_cast<int>(floorf((px - halfX) * s.scaleX));
    const int x1 = static_cast<int>(floorf((px + halfX) * s.scaleX));
    const int y0 = static_cast<int>(floorf((py - halfY) * s.scaleY));
    const int y1 = static_cast<int>(floorf((py + halfY) * s.scaleY));
    out.kind = BlockSquare::Kind::Square;
    out.x0 = x0 > 0 ? x0 : 0;
    out.x1 = x1 < s.w - 1 ? x1 : s.w - 1;
    out.y0 = y0 > 0 ? y0 : 0;
    out.y1 = y1 < s.h - 1 ? y1 : s.h - 1;
    out.tEnter = dist - radius;
    out.tExit = dist + radius;
    return out;
}

}  // namespace minmax

class MinMaxBuffer {
  public:
    // `resolution` buffer pixels along the image's longer side (e.g. 64, 128, 256).
    static MinMaxBuffer build(const GridView& grid, const Camera& camera, int resolution);

    // The interval a primary ray through image pixel (x, y) must traverse; empty (t0 > t1) if none.
    void range(int x, int y, float& t0, float& t1) const { view().range(x, y, t0, t1); }

    // Its view; none (every range whole) for a buffer never built.
    MinMaxView view() const {
        if (m_min.empty()) return {};
        return {m_min.data(), m_max.data(), m_shape, m_everything};
    }
    int width() const { return m_shape.w; }
    int height() const { return m_shape.h; }
    size_t squares() const { return m_squares; }
    // Per buffer pixel, row by row: the smallest entry (+inf where no square covers it) and the
    // largest exit (-inf there).
    const std::vector<float>& minimum() const { return m_min; }
    const std::vector<float>& maximum() const { return m_max; }
    bool everything() const { return m_everything; }

  private:
    MinMaxShape m_shape;
    bool m_everything = false;
    std::vector<float> m_min, m_max;
    size_t m_squares = 0;
};

}  // namespace sdft
