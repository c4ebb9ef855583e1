#include "sdftrace/trace/minmax_buffer.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace sdft {

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

    const Vec3 forward = cam.forward(), right = cam.right(), up = cam.up();
    const float tanHalf = cam.tanHalfFov();
    const int B = g.kind == GridKind::Sparse
                      ? g.blockSize
                      : std::max({g.shape.cells[0], g.shape.cells[1], g.shape.cells[2]});
    const int nb[3] = {g.kind == GridKind::Sparse ? g.blocks[0] : 1,
                       g.kind == GridKind::Sparse ? g.blocks[1] : 1,
                       g.kind == GridKind::Sparse ? g.blocks[2] : 1};
    const float h = g.shape.voxelSize;
    const float radius = 0.5f * std::sqrt(3.0f) * B * h;  // bounding sphere of a block
    // Blocks are rasterized in parallel slices into thread-local buffers, merged at the end (the
    // buffers are small: a few hundred KiB at 256^2).
    struct Local {
        std::vector<float> lo, hi;
        size_t squares = 0;
        bool everything = false;
    };
    tbb::enumerable_thread_specific<Local> locals([&] {
        return Local{std::vector<float>(b.m_min.size(), kInfinity),
                     std::vector<float>(b.m_max.size(), -kInfinity)};
    });
    tbb::parallel_for(
        tbb::blocked_range<int>(0, nb[2]), [&](const tbb::blocked_range<int>& slices) {
            Local& L = locals.local();
            for (int k = slices.begin(); k != slices.end(); ++k)
                for (int j = 0; j < nb[1]; ++j)
                    for (int i = 0; i < nb[0]; ++i) {
                        if (g.kind == GridKind::Sparse &&
                            g.flags[(static_cast<size_t>(k) * nb[1] + j) * nb[0] + i] !=
                                static_cast<uint8_t>(BlockFlag::Surface))
                            continue;
                        Vec3 c = g.shape.origin + (Vec3(i, j, k) + Vec3(0.5f)) * (B * h);
                        Vec3 rel = c - d.eye;
                        float dist = length(rel);
                        float z = dot(rel, forward);
                        ++L.squares;
                        if (z - radius <= 1e-6f * dist || dist <= radius) {
                            L.everything = true;  // the sphere reaches the camera plane: no bound
                            continue;
                        }
                        // Centre in image pixels and a conservative half-width per axis. A sphere
                        // point q = c + e (|e| <= r) projects to q_x / q_z; |q_x/q_z - c_x/c_z| =
                        // |e_x c_z - c_x e_z| / (q_z c_z) <= r (c_z + |c_x|) / ((c_z - r) c_z).
                        float cx = dot(rel, right), cy = dot(rel, up);
                        float px, py;
                        cam.project(c, px, py);
                        float pixelsPerUnit =
                            0.5f * d.height / tanHalf;  // image-plane units to pixels
                        float halfX =
                            radius * (z + std::fabs(cx)) / ((z - radius) * z) * pixelsPerUnit;
                        float halfY =
                            radius * (z + std::fabs(cy)) / ((z - radius) * z) * pixelsPerUnit;
                        int x0 =
                            std::max(0, static_cast<int>(std::floor((px - halfX) * b.m_scaleX)));
                        int x1 = std::min(b.m_w - 1,
                                          static_cast<int>(std::floor((px + halfX) * b.m_scaleX)));
                        int y0 =
                            std::max(0, static_cast<int>(std::floor((py - halfY) * b.m_scaleY)));
                        int y1 = std::min(b.m_h - 1,
                                          static_cast<int>(std::floor((py + halfY) * b.m_scaleY)));
                        float tEnter = dist - radius, tExit = dist + radius;
                        for (int y = y0; y <= y1; ++y)
                            for (int x = x0; x <= x1; ++x) {
                                size_t p = static_cast<size_t>(y) * b.m_w + x;
                                L.lo[p] = std::min(L.lo[p], tEnter);
                                L.hi[p] = std::max(L.hi[p], tExit);
                            }
                    }
        });
    for (const Local& L : locals) {
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
