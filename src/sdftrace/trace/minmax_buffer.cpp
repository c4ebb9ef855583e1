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

void splat(const BlockSquare& sq, int w, LocalBuffers& L) {
    if (sq.kind == BlockSquare::Kind::Unseen) return;
    ++L.squares;
    if (sq.kind == BlockSquare::Kind::Everything) {
        L.everything = true;
        return;
    }
    for (int y = sq.y0; y <= sq.y1; ++y)
        for (int x = sq.x0; x <= sq.x1; ++x) {
            const size_t p = static_cast<size_t>(y) * w + x;
            L.lo[p] = std::min(L.lo[p], sq.tEnter);
            L.hi[p] = std::max(L.hi[p], sq.tExit);
        }
}

}  // namespace

MinMaxShape minMaxShape(const CameraDesc& d, int resolution) {
    MinMaxShape s;
    const float longer = static_cast<float>(std::max(d.width, d.height));
    s.w = std::max(1, static_cast<int>(std::ceil(d.width * resolution / longer)));
    s.h = std::max(1, static_cast<int>(std::ceil(d.height * resolution / longer)));
    s.scaleX = static_cast<float>(s.w) / d.width;
    s.scaleY = static_cast<float>(s.h) / d.height;
    return s;
}

MinMaxBuffer MinMaxBuffer::build(const GridView& g, const Camera& cam, int resolution) {
    MinMaxBuffer b;
    b.m_shape = minMaxShape(cam.desc(), resolution);
    const size_t n = static_cast<size_t>(b.m_shape.w) * b.m_shape.h;
    b.m_min.assign(n, kInfinity);
    b.m_max.assign(n, -kInfinity);
    const float radius = minmax::blockRadius(g);
    int nb[3];
    minmax::blockCounts(g, nb);
    // Surface blocks are splatted in parallel slices of tiles into thread-local buffers; a tile
    // without a page of its own holds none.
    tbb::enumerable_thread_specific<LocalBuffers> locals([&] {
        return LocalBuffers{std::vector<float>(n, kInfinity), std::vector<float>(n, -kInfinity)};
    });
    const bool sparse = g.kind == GridKind::Sparse;
    const size_t tx = sparse ? g.tiles[0] : 1, ty = sparse ? g.tiles[1] : 1,
                 tz = sparse ? g.tiles[2] : 1;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, tx * ty * tz, 64), [&](const auto& range) {
        LocalBuffers& L = locals.local();
        for (size_t tile = range.begin(); tile != range.end(); ++tile) {
            if (sparse && g.tilePage[tile] < kFirstOwnPage) continue;
            const int t[3] = {static_cast<int>(tile % tx), static_cast<int>(tile / tx % ty),
                              static_cast<int>(tile / (tx * ty))};
            forEachBlockOfTile(nb, t[0], t[1], t[2], [&](int i, int j, int k) {
                Vec3 c;
                if (minmax::splattedBlock(g, i, j, k, c))
                    splat(minmax::blockSquare(cam, c, radius, b.m_shape), b.m_shape.w, L);
            });
        }
    });
    for (const LocalBuffers& L : locals) {
        b.m_squares += L.squares;
        b.m_everything |= L.everything;
        for (size_t p = 0; p < n; ++p) {
            b.m_min[p] = std::min(b.m_min[p], L.lo[p]);
            b.m_max[p] = std::max(b.m_max[p], L.hi[p]);
        }
    }
    return b;
}

}  // namespace sdft
