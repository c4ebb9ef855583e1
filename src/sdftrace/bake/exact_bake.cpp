#include "sdftrace/bake/exact_bake.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <array>
#include <atomic>
#include <memory>

#include "sdftrace/bake/closest_point.h"
#include "sdftrace/bake/winding_number.h"
#include "sdftrace/exec/progress.h"

namespace sdft {

namespace {

// Samples runs of vertices along +x with the row tricks of the header comment.
class RowSampler {
  public:
    RowSampler(const MeshBvh& bvh, const GridShape& shape, SignMethod sign)
        : m_bvh(bvh), m_shape(shape), m_sign(sign), m_watertight(isWatertight(bvh.mesh())) {
        if (sign == SignMethod::WindingNumber)
            m_winding = std::make_unique<WindingNumber>(bvh.mesh());
    }

    Vec3 position(int i, int j, int k) const {
        return m_shape.origin + Vec3(i, j, k) * m_shape.voxelSize;
    }

    bool watertight() const { return m_watertight; }

    bool inside(Vec3 p) const { return m_winding ? m_winding->inside(p) : m_bvh.insideByParity(p); }

    // Vertices (i0 + n', j, k), n' < n, into out[0, n).
    void row(int i0, int j, int k, int n, float* out, std::atomic<size_t>& queries,
             std::atomic<size_t>& signs) const {
        // 0.1% over the spacing: far above the rounding of the distances, so both the search
        // radius and the sign rule stay conservative.
        const float step = m_shape.voxelSize * 1.001f;
        float prev = INFINITY;
        Vec3 prevPoint;
        bool prevInside = false;
        size_t evaluated = 0;
        for (int n1 = 0; n1 < n; ++n1) {
            Vec3 p = position(i0 + n1, j, k);
            // The previous closest point bounds this distance (tighter than prev + h).
            MeshBvh::Closest c = prev == INFINITY
                                     ? m_bvh.closest(p)
                                     : m_bvh.closest(p, length(p - prevPoint) * 1.0001f + 1e-30f);
            if (c.distance == INFINITY) c = m_bvh.closest(p);  // unreachable but for rounding
            float d = c.distance;
            prevPoint = c.point;
            // Watertight: d > h means the ball around p holds no surface yet holds the previous
            // vertex, so no crossing lies between them.
            bool in;
            if (m_watertight && n1 > 0 && (d > step || prev > step)) {
                in = prevInside;
            } else {
                in = inside(p);
                ++evaluated;
            }
            out[n1] = in ? -d : d;
            prev = d;
            prevInside = in;
        }
        queries += n;
        signs += evaluated;
    }

  private:
    const MeshBvh& m_bvh;
    const GridShape& m_shape;
    SignMethod m_sign;
    bool m_watertight;
    std::unique_ptr<WindingNumber> m_winding;
};

int arenaThreads(int threads) {
    return threads > 0 ? threads : tbb::this_task_arena::max_concurrency();
}

void report(ExactBakeStats* stats, const std::atomic<size_t>& queries,
            const std::atomic<size_t>& signs) {
    if (!stats) return;
    stats->distanceQueries = queries.load();
    stats->signEvaluations = signs.load();
}

}  // namespace

std::vector<float> bakeExactSamples(const MeshBvh& bvh, const GridShape& s, SignMethod sign,
                                    int threads, ExactBakeStats* stats, bool progress) {
    RowSampler sampler(bvh, s, sign);
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    std::vector<float> out(s.vertexCount());
    std::atomic<size_t> queries{0}, signs{0};
    Progress bar("sdftrace bake: exact distances", static_cast<uint64_t>(vy) * vz,
                 progress && stderrIsTerminal());
    tbb::task_arena arena(arenaThreads(threads));
    arena.execute([&] {
        tbb::parallel_for(
            tbb::blocked_range<int>(0, vy * vz), [&](const tbb::blocked_range<int>& rows) {
                for (int row = rows.begin(); row != rows.end(); ++row) {
                    sampler.row(0, row % vy, row / vy, vx,
                                out.data() + static_cast<size_t>(row) * vx, queries, signs);
                }
                bar.advance(rows.size());
            });
    });
    report(stats, queries, signs);
    return out;
}

Grid bakeExactSparse(const MeshBvh& bvh, const GridShape& s, int B, float bandVoxels,
                     SignMethod sign, int threads, ExactBakeStats* stats, bool progress) {
    SDFT_CHECK(B == 4 || B == 8);
    SDFT_CHECK(bandVoxels >= 2);
    const TriangleMesh& mesh = bvh.mesh();
    RowSampler sampler(bvh, s, sign);
    const float h = s.voxelSize, reach = bandVoxels * h;
    const int nv[3] = {s.vertices(0), s.vertices(1), s.vertices(2)};
    const int nb[3] = {(s.cells[0] + B - 1) / B, (s.cells[1] + B - 1) / B,
                       (s.cells[2] + B - 1) / B};
    const size_t numBlocks = static_cast<size_t>(nb[0]) * nb[1] * nb[2];
    auto blockIndex = [&](int bi, int bj, int bk) {
        return (static_cast<size_t>(bk) * nb[1] + bj) * nb[0] + bi;
    };
    // Vertex v belongs to owner v / B; one more owner layer holds the last vertices of each axis.
    const int no[3] = {s.cells[0] / B + 1, s.cells[1] / B + 1, s.cells[2] / B + 1};
    const size_t numOwners = static_cast<size_t>(no[0]) * no[1] * no[2];
    auto ownerIndex = [&](int oi, int oj, int ok) {
        return (static_cast<size_t>(ok) * no[1] + oj) * no[0] + oi;
    };
    std::atomic<size_t> queries{0}, signs{0};
    tbb::task_arena arena(arenaThreads(threads));

    // 1. Scatter: a vertex closer than the band to the mesh is within the band of its closest
    // triangle's bounds, so each owner block lists the triangles whose bounds, grown by the band,
    // overlap its vertices; the minimum over them is exact there. Vertices farther away are
    // clamped to the band (as a narrow-band level set stores them).
    struct Range {
        int lo[3], hi[3];
    };
    std::vector<Range> ranges(mesh.triangles.size());
    std::vector<uint32_t> listStart(numOwners + 1, 0);
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const auto& tri = mesh.triangles[t];
        Vec3 a = mesh.positions[tri[0]], b = mesh.positions[tri[1]], c = mesh.positions[tri[2]];
        Vec3 lo = (min(a, min(b, c)) - s.origin - Vec3(reach)) / h;
        Vec3 hi = (max(a, max(b, c)) - s.origin + Vec3(reach)) / h;
        Range& r = ranges[t];
        for (int axis = 0; axis < 3; ++axis) {
            r.lo[axis] = std::max(0, static_cast<int>(std::ceil(lo[axis])));
            r.hi[axis] = std::min(nv[axis] - 1, static_cast<int>(std::floor(hi[axis])));
        }
        if (r.lo[0] > r.hi[0] || r.lo[1] > r.hi[1] || r.lo[2] > r.hi[2]) continue;
        for (int ok = r.lo[2] / B; ok <= r.hi[2] / B; ++ok)
            for (int oj = r.lo[1] / B; oj <= r.hi[1] / B; ++oj)
                for (int oi = r.lo[0] / B; oi <= r.hi[0] / B; ++oi)
                    ++listStart[ownerIndex(oi, oj, ok) + 1];
    }
    for (size_t o = 0; o < numOwners; ++o) listStart[o + 1] += listStart[o];
    std::vector<uint32_t> lists(listStart[numOwners]);
    {
        std::vector<uint32_t> fill(listStart.begin(), listStart.end() - 1);
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            const Range& r = ranges[t];
            if (r.lo[0] > r.hi[0] || r.lo[1] > r.hi[1] || r.lo[2] > r.hi[2]) continue;
            for (int ok = r.lo[2] / B; ok <= r.hi[2] / B; ++ok)
                for (int oj = r.lo[1] / B; oj <= r.hi[1] / B; ++oj)
                    for (int oi = r.lo[0] / B; oi <= r.hi[0] / B; ++oi)
                        lists[fill[ownerIndex(oi, oj, ok)]++] = static_cast<uint32_t>(t);
        }
    }
    auto listed = [&](int oi, int oj, int ok) {
        size_t o = ownerIndex(oi, oj, ok);
        return listStart[o + 1] > listStart[o];
    };

    // 2. Blocks none of whose owners list a triangle hold no vertex within the band, hence no
    // surface (it would pass within half a cell diagonal of a vertex): one sign for the block. The
    // others are candidates, and need all 8 of their owners.
    std::vector<uint8_t> flags(numBlocks, static_cast<uint8_t>(BlockFlag::Outside));
    std::vector<uint8_t> candidate(numBlocks, 0);
    std::vector<int32_t> slot(numOwners, -1);
    std::vector<uint8_t> rowNeeded(static_cast<size_t>(no[1]) * no[2], 0);
    for (int bk = 0; bk < nb[2]; ++bk)
        for (int bj = 0; bj < nb[1]; ++bj)
            for (int bi = 0; bi < nb[0]; ++bi) {
                bool any = false;
                for (int d = 0; d < 8 && !any; ++d) {
                    int oi = bi + (d & 1), oj = bj + ((d >> 1) & 1), ok = bk + (d >> 2);
                    any = oi < no[0] && oj < no[1] && ok < no[2] && listed(oi, oj, ok);
                }
                if (!any) continue;
                candidate[blockIndex(bi, bj, bk)] = 1;
                for (int d = 0; d < 8; ++d) {
                    int oi = bi + (d & 1), oj = bj + ((d >> 1) & 1), ok = bk + (d >> 2);
                    if (oi < no[0] && oj < no[1] && ok < no[2]) {
                        slot[ownerIndex(oi, oj, ok)] = 0;
                        rowNeeded[static_cast<size_t>(ok) * no[1] + oj] = 1;
                    }
                }
            }
    int32_t owners = 0;
    for (int32_t& sl : slot)
        if (sl == 0) sl = owners++;
    const size_t perOwner = static_cast<size_t>(B) * B * B;
    // Uninitialized: every needed owner fills its samples below.
    std::unique_ptr<float[]> owned(new float[static_cast<size_t>(owners) * perOwner]);

    // 3. Distances, one task per row of owners.
    const float step = h * 1.001f;
    const bool watertight = sampler.watertight();
    {
        Progress bar("sdftrace bake: narrow band", static_cast<uint64_t>(no[1]) * no[2],
                     progress && stderrIsTerminal());
        arena.execute([&] {
            tbb::parallel_for(0, no[1] * no[2], [&](int row) {
                const int oj = row % no[1], ok = row / no[1];
                size_t found = 0;
                for (int oi = 0; rowNeeded[row] && oi < no[0]; ++oi) {
                    size_t o = ownerIndex(oi, oj, ok);
                    int32_t sl = slot[o];
                    if (sl < 0) continue;
                    float* out = owned.get() + sl * perOwner;
                    std::fill(out, out + perOwner, reach);
                    const int i0 = oi * B, j0 = oj * B, k0 = ok * B;
                    for (uint32_t n = listStart[o]; n < listStart[o + 1]; ++n) {
                        const uint32_t t = lists[n];
                        const Range& r = ranges[t];
                        const auto& tri = mesh.triangles[t];
                        Vec3 a = mesh.positions[tri[0]], b = mesh.positions[tri[1]],
                             c = mesh.positions[tri[2]];
                        // Vertices farther than the band from the triangle's plane cannot be
                        // closer than the band to it (large triangles' boxes are mostly such).
                        Vec3 nrm = cross(b - a, c - a);
                        float slab = reach * reach * dot(nrm, nrm) * 1.0001f;
                        for (int k = std::max(k0, r.lo[2]); k <= std::min(k0 + B - 1, r.hi[2]); ++k)
                            for (int j = std::max(j0, r.lo[1]); j <= std::min(j0 + B - 1, r.hi[1]);
                                 ++j)
                                for (int i = std::max(i0, r.lo[0]);
                                     i <= std::min(i0 + B - 1, r.hi[0]); ++i) {
                                    Vec3 p = sampler.position(i, j, k);
                                    float plane = dot(p - a, nrm);
                                    if (plane * plane > slab) continue;
                                    float d = length(p - closestPointOnTriangle(p, a, b, c));
                                    float& best = out[((k - k0) * B + (j - j0)) * B + (i - i0)];
                                    best = std::fmin(best, d);
                                }
                    }
                    for (size_t v = 0; v < perOwner; ++v) found += out[v] < reach;
                }
                queries += found;
                bar.advance();
            });
        });
    }
    auto vertex = [&](int i, int j, int k) {
        i = std::min(i, s.cells[0]), j = std::min(j, s.cells[1]), k = std::min(k, s.cells[2]);
        int32_t sl = slot[ownerIndex(i / B, j / B, k / B)];
        return owned[sl * perOwner + (static_cast<size_t>(k % B) * B + j % B) * B + i % B];
    };

    // 4. Surface blocks: a (clamped, unsigned) sample within the band. A sign change needs the
    // surface between two vertices, hence one within half a cell diagonal: no other block holds
    // one. Only the vertices of surface blocks are signed one by one.
    const int V = B + 1;
    const size_t perBlock = static_cast<size_t>(V) * V * V;
    std::vector<uint8_t> keep(numBlocks, 0);
    arena.execute([&] {
        tbb::parallel_for(size_t(0), numBlocks, [&](size_t b) {
            if (!candidate[b]) return;
            int bi = static_cast<int>(b % nb[0]), bj = static_cast<int>((b / nb[0]) % nb[1]),
                bk = static_cast<int>(b / (static_cast<size_t>(nb[0]) * nb[1]));
            bool near = false;
            for (int k = 0; k < V && !near; ++k)
                for (int j = 0; j < V && !near; ++j)
                    for (int i = 0; i < V && !near; ++i)
                        near = vertex(bi * B + i, bj * B + j, bk * B + k) < reach;
            keep[b] = near;
        });
    });
    // Whether a vertex belongs to a surface block (v / B, or v / B - 1 on a shared face).
    auto needed = [&](int i, int j, int k) {
        int lo[3], hi[3], v[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) {
            hi[a] = std::min(v[a] / B, nb[a] - 1);
            lo[a] = v[a] % B == 0 && v[a] > 0 ? v[a] / B - 1 : hi[a];
        }
        for (int bk = lo[2]; bk <= hi[2]; ++bk)
            for (int bj = lo[1]; bj <= hi[1]; ++bj)
                for (int bi = lo[0]; bi <= hi[0]; ++bi)
                    if (keep[blockIndex(bi, bj, bk)]) return true;
        return false;
    };

    // 5. Signs of the surface blocks' vertices, one task per row of owners so that signs carry
    // along vertex rows (watertight meshes: the winding number only within a voxel of the
    // surface, at chain starts, and where a -y or -z neighbour cannot vouch).
    arena.execute([&] {
        tbb::parallel_for(0, no[1] * no[2], [&](int row) {
            const int oj = row % no[1], ok = row / no[1];
            if (!rowNeeded[row]) return;
            size_t evaluated = 0;
            for (int k = ok * B; k < std::min(ok * B + B, nv[2]); ++k)
                for (int j = oj * B; j < std::min(oj * B + B, nv[1]); ++j) {
                    float prev = -1;
                    bool prevInside = false;
                    for (int i = 0; i < nv[0]; ++i) {
                        int32_t sl = slot[ownerIndex(i / B, oj, ok)];
                        if (sl < 0) {
                            i = (i / B) * B + B - 1;  // skip the owner; the chain breaks
                            prev = -1;
                            continue;
                        }
                        if (!needed(i, j, k)) {
                            prev = -1;
                            continue;
                        }
                        float& v = owned[sl * perOwner + ((k % B) * B + (j % B)) * B + (i % B)];
                        const float d = v;
                        bool in;
                        float across = -1;  // the signed -y or -z neighbour in this owner
                        if (watertight && prev < 0 && (j % B != 0 || k % B != 0)) {
                            bool ny = j % B != 0;
                            if (ny ? needed(i, j - 1, k) : needed(i, j, k - 1))
                                across = ny ? owned[sl * perOwner +
                                                    ((k % B) * B + (j % B - 1)) * B + (i % B)]
                                            : owned[sl * perOwner +
                                                    ((k % B - 1) * B + (j % B)) * B + (i % B)];
                        }
                        if (watertight && prev >= 0 && (d > step || prev > step)) {
                            in = prevInside;
                        } else if (across != -1 && (d > step || std::fabs(across) > step)) {
                            in = across < 0;
                        } else {
                            in = sampler.inside(sampler.position(i, j, k));
                            ++evaluated;
                        }
                        v = in ? -d : d;
                        prev = d;
                        prevInside = in;
                    }
                }
            signs += evaluated;
        });
    });

    // 6. The other blocks take the sign at their centre: on a watertight mesh the previous
    // block's in the row when that one was not a surface block either (neither holds surface, and
    // the segment between the centres stays in them).
    std::atomic<size_t> centreSigns{0};
    arena.execute([&] {
        tbb::parallel_for(0, nb[1] * nb[2], [&](int row) {
            const int bj = row % nb[1], bk = row / nb[1];
            bool prevFree = false, prevInside = false;
            size_t evaluated = 0;
            for (int bi = 0; bi < nb[0]; ++bi) {
                size_t b = blockIndex(bi, bj, bk);
                if (keep[b]) {
                    flags[b] = static_cast<uint8_t>(BlockFlag::Surface);
                    prevFree = false;
                    continue;
                }
                bool in = prevInside;
                if (!(watertight && prevFree)) {
                    Vec3 lo = sampler.position(bi * B, bj * B, bk * B);
                    Vec3 hi = sampler.position(std::min(bi * B + B, s.cells[0]),
                                               std::min(bj * B + B, s.cells[1]),
                                               std::min(bk * B + B, s.cells[2]));
                    in = sampler.inside((lo + hi) * 0.5f);
                    ++evaluated;
                }
                flags[b] = static_cast<uint8_t>(in ? BlockFlag::Inside : BlockFlag::Outside);
                prevFree = true;
                prevInside = in;
            }
            centreSigns += evaluated;
        });
    });
    signs += centreSigns.load();
    std::vector<size_t> kept;
    for (size_t b = 0; b < numBlocks; ++b)
        if (keep[b]) kept.push_back(b);
    std::vector<float> blockSamples(kept.size() * perBlock);
    arena.execute([&] {
        tbb::parallel_for(size_t(0), kept.size(), [&](size_t n) {
            size_t b = kept[n];
            int bi = static_cast<int>(b % nb[0]), bj = static_cast<int>((b / nb[0]) % nb[1]),
                bk = static_cast<int>(b / (static_cast<size_t>(nb[0]) * nb[1]));
            float* out = blockSamples.data() + n * perBlock;
            for (int k = 0; k < V; ++k)
                for (int j = 0; j < V; ++j)
                    for (int i = 0; i < V; ++i) *out++ = vertex(bi * B + i, bj * B + j, bk * B + k);
        });
    });
    report(stats, queries, signs);
    if (stats) stats->surfaceBlocks = kept.size();
    Grid grid;
    arena.execute([&] {
        grid = Grid::sparseFromBuffers(s, B, (bandVoxels - 1) * h, std::move(flags),
                                       std::move(blockSamples), "exact bake");
    });
    return grid;
}

Grid bakeMeshExact(const TriangleMesh& mesh, const SampleOptions& o, SignMethod sign) {
    MeshBvh bvh(mesh);
    GridShape shape = gridShapeFor(mesh.bounds(), o);
    if (o.kind == GridKind::Sparse)
        return bakeExactSparse(bvh, shape, o.blockSize, o.bandVoxels, sign, o.threads);
    return Grid::dense(shape, bakeExactSamples(bvh, shape, sign, o.threads));
}

}  // namespace sdft
