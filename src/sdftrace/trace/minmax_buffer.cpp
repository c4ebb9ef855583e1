#include "sdftrace/trace/minmax_buffer.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace sdft {

namespace {

// One thread's buffers, merged at the end (they are small: a few hundred KiB at 256^2).
struct LocalBuffers {
    std::vector<float> lo, hi;
    size_t squares = 0;
    bool everything = false;
};

// Jamriška §6: the square a block's bounding sphere (centre c, radius r) covers on the image,
// widened conservatively, takes min(t_enter) and max(t_exit) of the sphere.
void splatBlock(const Camera& cam, Vec3 c, float radius, int w, int h, float scaleX, float scaleY,
                LocalBuffers& L) {
    const CameraDesc& d = cam.desc();
    const Vec3 rel = c - d.eye;
    const float dist = length(rel), z = dot(rel, cam.forward());
    const float cx = dot(rel, cam.right()), cy = dot(rel, cam.up());
    // A primary ray leaves the eye into the view frustum (|x| <= z tx, |y| <= z ty): a sphere
    // behind the camera plane or outside one of the frustum's four side planes is never met.
    const float ty = cam.tanHalfFov(), tx = ty * static_cast<float>(d.width) / d.height;
    if (z + radius < 0 || (std::fabs(cx) - z * tx) > radius * std::sqrt(1 + tx * tx) ||
        (std::fabs(cy) - z * ty) > radius * std::sqrt(1 + ty * ty))
        return;
    ++L.squares;
    if (z - radius <= 1e-6f * dist || dist <= radius) {
        L.everything = true;  // the sphere reaches the camera plane: no bound
        return;
    }
    // Centre in image pixels and a conservative half-width per axis. A sphere point q = c + e
    // (|e| <= r) projects to q_x / q_z; |q_x/q_z - c_x/c_z| = |e_x c_z - c_x e_z| / (q_z c_z)
    // <= r (c_z + |c_x|) / ((c_z - r) c_z).
    float px = 0, py = 0;  // z > r > 0: the centre projects
    cam.project(c, px, py);
    const float pixelsPerUnit = 0.5f * d.height / cam.tanHalfFov();  // image plane to pixels
    const float halfX = radius * (z + std::fabs(cx)) / ((z - radius) * z) * pixelsPerUnit;
    const float halfY = radius * (z + std::fabs(cy)) / ((z - radius) * z) * pixelsPerUnit;
    const int x0 = std::max(0, static_cast<int>(std::floor((px - halfX) * scaleX)));
    const int x1 = std::min(w - 1, static_cast<int>(std::floor((px + halfX) * scaleX)));
    const int y0 = std::max(0, static_cast<int>(std::floor((py - halfY) * scaleY)));
    const int y1 = std::min(h - 1, static_cast<int>(std::floor((py + halfY) * scaleY)));
    const float tEnter = dist - radius, tExit = dist + radius;
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
            const size_t p = static_cast<size_t>(y) * w + x;
            L.lo[p] = std::min(L.lo[p], tEnter);
            L.hi[p] = std::max(L.hi[p], tExit);
        }
}

}  // namespace

MinMaxBuffer MinMaxBuffer::build(const GridView& g, const Camera& cam, int resolution) {
    const CameraDesc& d = cam.desc();
    MinMaxBuffer b;
    float longer = static_cast<float>(std::max(d.width, d.height));
    b.m_w = std::max(1, static_cast<int>(std::ceil(d.width * resolution / longer)));
    b.m_h = std::max(1, static_cast<int>(std::ceil(d.height * resolution / longer)));
    b.m_scaleX = static_cast<float>(b.m_w) / d.width;
    b.m_scaleY = static_cast<float>(b.m_h) / d.height;
    b.m_min.assign(static_cast<size_t>(b.m_w) * b.m_h, kInfinity);
    b.m_max.assign(static_cast<size_t>(b.m_w) * b.m_h, -kInfinity);
    const bool sparse = g.kind == GridKind::Sparse;
    const int B =
        sparse ? g.blockSize : std::max({g.shape.cells[0], g.shape.cells[1], g.shape.cells[2]});
    const int nb[3] = {sparse ? g.blocks[0] : 1, sparse ? g.blocks[1] : 1,
                       sparse ? g.blocks[2] : 1};
    const float h = g.shape.voxelSize;
    const float radius = 0.5f * std::sqrt(3.0f) * B * h;  // bounding sphere of a block
    // Surface blocks are splatted in parallel slices into thread-local buffers.
    tbb::enumerable_thread_specific<LocalBuffers> locals([&] {
        return LocalBuffers{std::vector<float>(b.m_min.size(), kInfinity),
                            std::vector<float>(b.m_max.size(), -kInfinity)};
    });
    // Only blocks a ray can hit in (the DDA walks no other): the blocks of a dense grid's one
    // block, or of a sparse grid's own pages (block_table.h).
    const size_t tiles = sparse ? static_cast<size_t>(g.tiles[0]) * g.tiles[1] * g.tiles[2] : 1;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, tiles, 64), [&](const auto& range) {
        LocalBuffers& L = locals.local();
        for (size_t tile = range.begin(); tile != range.end(); ++tile) {
            if (!sparse) {
                const Vec3 c = g.shape.origin + Vec3(0.5f) * (B * h);
                splatBlock(cam, c, radius, b.m_w, b.m_h, b.m_scaleX, b.m_scaleY, L);
                continue;
            }
            const int32_t page = g.tilePage[tile];
            if (page < kFirstOwnPage) continue;
            const int t[3] = {
                static_cast<int>(tile % g.tiles[0]),
                static_cast<int>(tile / g.tiles[0] % g.tiles[1]),
                static_cast<int>(tile / (static_cast<size_t>(g.tiles[0]) * g.tiles[1]))};
            forEachBlockOfTile(nb, t[0], t[1], t[2], [&](int i, int j, int k) {
                if (!g.mayHoldHit(static_cast<size_t>(page) * kPageEntries + pageLocal(i, j, k)))
                    return;
                const Vec3 c = g.shape.origin + (Vec3(i, j, k) + Vec3(0.5f)) * (B * h);
                splatBlock(cam, c, radius, b.m_w, b.m_h, b.m_scaleX, b.m_scaleY, L);
            });
        }
    });
    for (const LocalBuffers& L : locals) {
        b.m_squares += L.squares;
        b.m_everything |= L.everything;
        for (size_t p = 0; p < b.m_min.size(); ++p) {
            b.m_min[p] = std::min(b.m_min[p], L.lo[p]);
            b.m_max[p] = std::max(b.m_max[p], L.hi[p]);
        }
    }
    return b;
}

void MinMaxBuffer::range(int x, int y, float& t0, float& t1) const {
    if (m_everything) {
        t0 = 0;
        t1 = kInfinity;
        return;
    }
    int bx = std::min(m_w - 1, static_cast<int>((x + 0.5f) * m_scaleX));
    int by = std::min(m_h - 1, static_cast<int>((y + 0.5f) * m_scaleY));
    size_t p = static_cast<size_t>(by) * m_w + bx;
    t0 = std::max(0.0f, m_min[p]);
    t1 = m_max[p];
}

}  // namespace sdft
