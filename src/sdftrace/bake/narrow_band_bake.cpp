// The exact narrow-band bake (exact_bake.h: bakeExactSparse): triangles scattered to the vertices
// within the band of their bounds, surface blocks decided from unsigned distances, signs carried
// between neighbours on watertight meshes.
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <array>
#include <atomic>

#include "exact_sampler.h"
#include "sdftrace/bake/closest_point.h"
#include "sdftrace/bake/exact_bake.h"
#include "sdftrace/bake/surface_seeds.h"
#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/exec/progress.h"

namespace sdft {

using detail::arenaThreads;
using detail::report;
using detail::RowSampler;

Grid bakeExactSparse(const MeshBvh& bvh, const GridShape& s, int B, float bandVoxels,
                     SignMethod sign, int threads, ExactBakeStats* stats, bool progress) {
    SDFT_CHECK(B == 4 || B == 8);
    // B is 4 or 8: shifts and masks instead of divisions in the per-vertex index arithmetic.
    const int shift = B == 4 ? 2 : 3, mask = B - 1;
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
    // Vertex v belongs to owner (v >> shift); one more owner layer holds the last vertices of each
    // axis.
    const int no[3] = {(s.cells[0] >> shift) + 1, (s.cells[1] >> shift) + 1,
                       (s.cells[2] >> shift) + 1};
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
    // Per owner, the triangles whose bounds grown by `grow` overlap its vertices (a prefix-summed
    // list), and per triangle its vertex range.
    struct OwnerLists {
        std::vector<VertexRange> ranges;
        std::vector<uint32_t> start, items;
    };
    auto binTriangles = [&](float grow) {
        OwnerLists l;
        l.ranges.resize(mesh.triangles.size());
        assignHuge(l.start, numOwners + 1, 0u);
        auto forOwners = [&](const VertexRange& r, auto&& f) {
            for (int ok = (r.lo[2] >> shift); ok <= (r.hi[2] >> shift); ++ok)
                for (int oj = (r.lo[1] >> shift); oj <= (r.hi[1] >> shift); ++oj)
                    for (int oi = (r.lo[0] >> shift); oi <= (r.hi[0] >> shift); ++oi)
                        f(ownerIndex(oi, oj, ok));
        };
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            const auto& tri = mesh.triangles[t];
            const VertexRange& r = l.ranges[t] = triangleVertexRange(
                s, mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]], grow);
            if (r.empty()) continue;
            forOwners(r, [&](size_t o) { ++l.start[o + 1]; });
        }
        for (size_t o = 0; o < numOwners; ++o) l.start[o + 1] += l.start[o];
        assignHuge(l.items, l.start[numOwners], 0u);
        std::vector<uint32_t> fill(l.start.begin(), l.start.end() - 1);
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            const VertexRange& r = l.ranges[t];
            if (r.empty()) continue;
            forOwners(r, [&](size_t o) { l.items[fill[o]++] = static_cast<uint32_t>(t); });
        }
        return l;
    };
    const OwnerLists bandLists = binTriangles(reach);
    const std::vector<VertexRange>& ranges = bandLists.ranges;
    const std::vector<uint32_t>& listStart = bandLists.start;
    const std::vector<uint32_t>& lists = bandLists.items;
    auto listed = [&](int oi, int oj, int ok) {
        size_t o = ownerIndex(oi, oj, ok);
        return listStart[o + 1] > listStart[o];
    };

    // 2. Blocks none of whose owners list a triangle hold no vertex within the band, hence no
    // surface (it would pass within half a cell diagonal of a vertex): one sign for the block. The
    // others are candidates, and need all 8 of their owners.
    std::vector<uint8_t> flags, candidate;
    assignHuge(flags, numBlocks, static_cast<uint8_t>(BlockFlag::Outside));
    assignHuge(candidate, numBlocks, uint8_t{0});
    std::vector<int32_t> slot;
    assignHuge(slot, numOwners, -1);
    std::vector<uint8_t> rowNeeded(static_cast<size_t>(no[1]) * no[2], 0);
    arena.execute([&] {
        tbb::parallel_for(0, nb[2], [&](int bk) {
            for (int bj = 0; bj < nb[1]; ++bj)
                for (int bi = 0; bi < nb[0]; ++bi) {
                    bool any = false;
                    for (int d = 0; d < 8 && !any; ++d) {
                        int oi = bi + (d & 1), oj = bj + ((d >> 1) & 1), ok = bk + (d >> 2);
                        any = oi < no[0] && oj < no[1] && ok < no[2] && listed(oi, oj, ok);
                    }
                    candidate[blockIndex(bi, bj, bk)] = any;
                }
        });
        // An owner is needed by the candidates among the (up to 8) blocks that use its vertices.
        tbb::parallel_for(0, no[2], [&](int ok) {
            for (int oj = 0; oj < no[1]; ++oj) {
                bool row = false;
                for (int oi = 0; oi < no[0]; ++oi) {
                    bool any = false;
                    for (int d = 0; d < 8 && !any; ++d) {
                        int bi = oi - (d & 1), bj = oj - ((d >> 1) & 1), bk = ok - (d >> 2);
                        any = bi >= 0 && bj >= 0 && bk >= 0 && bi < nb[0] && bj < nb[1] &&
                              bk < nb[2] && candidate[blockIndex(bi, bj, bk)];
                    }
                    if (any) slot[ownerIndex(oi, oj, ok)] = 0;
                    row |= any;
                }
                rowNeeded[static_cast<size_t>(ok) * no[1] + oj] = row;
            }
        });
    });
    int32_t owners = 0;
    for (int32_t& sl : slot)
        if (sl == 0) sl = owners++;
    const size_t perOwner = static_cast<size_t>(B) * B * B;
    std::vector<float> owned;
    assignHuge(owned, static_cast<size_t>(owners) * perOwner, 0.0f);

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
                    float* out = owned.data() + sl * perOwner;
                    std::fill(out, out + perOwner, reach);
                    const int i0 = oi * B, j0 = oj * B, k0 = ok * B;
                    for (uint32_t n = listStart[o]; n < listStart[o + 1]; ++n) {
                        const uint32_t t = lists[n];
                        const VertexRange& r = ranges[t];
                        const auto& tri = mesh.triangles[t];
                        Vec3 a = mesh.positions[tri[0]], b = mesh.positions[tri[1]],
                             c = mesh.positions[tri[2]];
                        // Lower bounds of the distance to the triangle, its plane's and its
                        // bounding sphere's, skip vertices it cannot bring below their best so
                        // far (the band to begin with).
                        Vec3 nrm = cross(b - a, c - a);
                        float invN2 = 1.0f / std::fmax(dot(nrm, nrm), 1e-37f);
                        Vec3 centre = (a + b + c) / 3.0f;
                        float radius = std::sqrt(std::fmax(
                            dot(a - centre, a - centre),
                            std::fmax(dot(b - centre, b - centre), dot(c - centre, c - centre))));
                        for (int k = std::max(k0, r.lo[2]); k <= std::min(k0 + B - 1, r.hi[2]); ++k)
                            for (int j = std::max(j0, r.lo[1]); j <= std::min(j0 + B - 1, r.hi[1]);
                                 ++j)
                                for (int i = std::max(i0, r.lo[0]);
                                     i <= std::min(i0 + B - 1, r.hi[0]); ++i) {
                                    Vec3 p = sampler.position(i, j, k);
                                    float& best = out[((k - k0) * B + (j - j0)) * B + (i - i0)];
                                    float plane = dot(p - a, nrm);
                                    // 0.9999: margins far above the rounding of both bounds.
                                    if (plane * plane * invN2 * 0.9999f > best * best) continue;
                                    float reachOut = best + radius;
                                    if (dot(p - centre, p - centre) * 0.9999f > reachOut * reachOut)
                                        continue;
                                    float d = length(p - closestPointOnTriangle(p, a, b, c));
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
        int32_t sl = slot[ownerIndex((i >> shift), (j >> shift), (k >> shift))];
        return owned[sl * perOwner + (static_cast<size_t>((k & mask)) * B + (j & mask)) * B +
                     (i & mask)];
    };

    // 4. Surface blocks: a (clamped, unsigned) sample within the band. A sign change needs the
    // surface between two vertices, hence one within half a cell diagonal: no other block holds
    // one. Only the vertices of surface blocks are signed one by one.
    const int V = B + 1;
    const size_t perBlock = static_cast<size_t>(V) * V * V;
    std::vector<uint8_t> keep;
    assignHuge(keep, numBlocks, uint8_t{0});
    // Per owned vertex: whether a surface block holds it (set from every such block).
    std::vector<uint8_t> neededFlag;
    assignHuge(neededFlag, static_cast<size_t>(owners) * perOwner, uint8_t{0});
    auto localIndex = [&](int i, int j, int k) {
        i = std::min(i, s.cells[0]), j = std::min(j, s.cells[1]), k = std::min(k, s.cells[2]);
        return slot[ownerIndex((i >> shift), (j >> shift), (k >> shift))] * perOwner +
               (static_cast<size_t>((k & mask)) * B + (j & mask)) * B + (i & mask);
    };
    // A candidate block is a surface block when one of its samples lies within the band; its
    // vertices then need signs.
    auto markSurface = [&](size_t b) {
        int bi = static_cast<int>(b % nb[0]), bj = static_cast<int>((b / nb[0]) % nb[1]),
            bk = static_cast<int>(b / (static_cast<size_t>(nb[0]) * nb[1]));
        bool near = false;
        for (int k = 0; k < V && !near; ++k)
            for (int j = 0; j < V && !near; ++j)
                for (int i = 0; i < V && !near; ++i)
                    near = vertex(bi * B + i, bj * B + j, bk * B + k) < reach;
        keep[b] = near;
    };
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, numBlocks, 1024), [&](const auto& range) {
            for (size_t b = range.begin(); b != range.end(); ++b)
                if (candidate[b]) markSurface(b);
        });
        // A vertex is needed when a surface block holds it: block v >> shift, and the one before
        // on a shared face (v a multiple of B).
        tbb::parallel_for(0, no[2], [&](int ok) {
            for (int oj = 0; oj < no[1]; ++oj)
                for (int oi = 0; oi < no[0]; ++oi) {
                    int32_t sl = slot[ownerIndex(oi, oj, ok)];
                    if (sl < 0) continue;
                    uint8_t* out = neededFlag.data() + sl * perOwner;
                    for (int lk = 0; lk < B; ++lk)
                        for (int lj = 0; lj < B; ++lj)
                            for (int li = 0; li < B; ++li) {
                                int lo[3], hi[3];
                                const int v[3] = {oi * B + li, oj * B + lj, ok * B + lk};
                                for (int a = 0; a < 3; ++a) {
                                    hi[a] = std::min(v[a] >> shift, nb[a] - 1);
                                    lo[a] = (v[a] & mask) == 0 && v[a] > 0 ? (v[a] >> shift) - 1
                                                                           : hi[a];
                                }
                                bool any = false;
                                for (int bk = lo[2]; bk <= hi[2] && !any; ++bk)
                                    for (int bj = lo[1]; bj <= hi[1] && !any; ++bj)
                                        for (int bi = lo[0]; bi <= hi[0] && !any; ++bi)
                                            any = keep[blockIndex(bi, bj, bk)];
                                out[(lk * B + lj) * B + li] = any;
                            }
                }
        });
    });
    // Per triangle: bounds, unit normal and twice the area, for the crossing tests.
    struct Plane {
        Vec3 lo, hi, normal;
        float area2;
    };
    const bool integerWinding = watertight && sampler.hasWinding();
    std::vector<Plane> planes(integerWinding ? mesh.triangles.size() : 0);
    for (size_t t = 0; t < planes.size(); ++t) {
        const auto& tri = mesh.triangles[t];
        Vec3 t0 = mesh.positions[tri[0]], t1 = mesh.positions[tri[1]], t2 = mesh.positions[tri[2]];
        Vec3 n = cross(t1 - t0, t2 - t0);
        float len = length(n);
        planes[t] = {min(t0, min(t1, t2)), max(t0, max(t1, t2)), len > 0 ? n / len : Vec3(0.0f),
                     len};
    }
    // Triangles meeting a segment of length h that ends at a vertex come within h of it: the
    // crossing tests read lists grown by one voxel only.
    const OwnerLists nearLists = integerWinding ? binTriangles(1.01f * h) : OwnerLists{};
    auto crossings = [&](Vec3 a, Vec3 b, size_t o, int& delta) {
        const float eps = 1e-5f * h;
        const Vec3 slo = min(a, b) - Vec3(eps), shi = max(a, b) + Vec3(eps);
        delta = 0;
        for (uint32_t n = nearLists.start[o]; n < nearLists.start[o + 1]; ++n) {
            const uint32_t t = nearLists.items[n];
            const Plane& pl = planes[t];
            if (pl.area2 == 0 || pl.lo.x > shi.x || pl.lo.y > shi.y || pl.lo.z > shi.z ||
                pl.hi.x < slo.x || pl.hi.y < slo.y || pl.hi.z < slo.z)
                continue;
            const auto& tri = mesh.triangles[t];
            Vec3 t0 = mesh.positions[tri[0]], t1 = mesh.positions[tri[1]],
                 t2 = mesh.positions[tri[2]];
            float da = dot(a - t0, pl.normal), db = dot(b - t0, pl.normal);
            if ((da > eps && db > eps) || (da < -eps && db < -eps)) continue;
            if (std::fabs(da - db) < eps) return false;  // along the plane
            Vec3 x = a + (b - a) * (da / (da - db));
            float u = dot(cross(t1 - x, t2 - x), pl.normal) / pl.area2,
                  v = dot(cross(t2 - x, t0 - x), pl.normal) / pl.area2, w = 1 - u - v;
            float lo = std::fmin(u, std::fmin(v, w));
            if (lo < -1e-5f) continue;  // misses the triangle
            // Near an edge or corner, or an end on the surface: undecided.
            if (lo < 1e-5f || std::fabs(da) <= eps || std::fabs(db) <= eps) return false;
            delta += da > 0 ? 1 : -1;
        }
        return true;
    };

    // 5. Signs of the surface blocks' vertices, one task per row of owners so that signs carry
    // along vertex rows. On a watertight mesh the winding number is an integer: it is carried
    // from the previous vertex of the row (or the -y / -z one at a chain start) unchanged where
    // one of the two is farther than a voxel from the surface, and through the signed crossings
    // of the segment between them otherwise; it is evaluated only where no neighbour can vouch.
    std::vector<int8_t> winding;
    assignHuge(winding, integerWinding ? static_cast<size_t>(owners) * perOwner : 0, int8_t{0});
    arena.execute([&] {
        // One task per slab of owners (B vertex layers in z): within it every vertex's -y and -z
        // neighbours are signed before it.
        tbb::parallel_for(0, no[2], [&](int ok) {
            size_t evaluated = 0;
            for (int k = ok * B; k < std::min(ok * B + B, nv[2]); ++k)
                for (int j = 0; j < nv[1]; ++j) {
                    const int oj = j >> shift;
                    if (!rowNeeded[static_cast<size_t>(ok) * no[1] + oj]) {
                        j = oj * B + B - 1;
                        continue;
                    }
                    float prev = -1;
                    bool prevInside = false;
                    int prevWinding = 0;
                    for (int i = 0; i < nv[0]; ++i) {
                        const size_t o = ownerIndex((i >> shift), oj, ok);
                        int32_t sl = slot[o];
                        if (sl < 0) {
                            i = ((i >> shift)) * B + B - 1;  // skip the owner; the chain breaks
                            prev = -1;
                            continue;
                        }
                        const size_t local =
                            sl * perOwner + (((k & mask)) * B + ((j & mask))) * B + ((i & mask));
                        if (!neededFlag[local]) {
                            prev = -1;
                            continue;
                        }
                        float& v = owned[local];
                        const float d = v;
                        const Vec3 p = sampler.position(i, j, k);
                        // The vouching neighbour: the previous vertex of the chain, else the
                        // signed -y one, else the -z one in this slab.
                        bool have = prev >= 0;
                        float nd = prev;
                        bool nInside = prevInside;
                        int nWinding = prevWinding;
                        Vec3 np = sampler.position(i - 1, j, k);
                        auto vouch = [&](int ni, int nj, int nk) {
                            int32_t ns = slot[ownerIndex(ni >> shift, nj >> shift, nk >> shift)];
                            if (ns < 0) return false;
                            size_t nl =
                                ns * perOwner + ((nk & mask) * B + (nj & mask)) * B + (ni & mask);
                            if (!neededFlag[nl]) return false;
                            nd = std::fabs(owned[nl]);
                            nInside = owned[nl] < 0;
                            if (integerWinding) nWinding = winding[nl];
                            np = sampler.position(ni, nj, nk);
                            return true;
                        };
                        if (watertight && !have)
                            have =
                                (j > 0 && vouch(i, j - 1, k)) || (k > ok * B && vouch(i, j, k - 1));
                        bool in;
                        int w = 0;
                        int delta = 0;
                        if (watertight && have && (d > step || nd > step)) {
                            in = nInside;
                            w = nWinding;
                        } else if (integerWinding && have && crossings(np, p, o, delta)) {
                            w = nWinding + delta;
                            in = w > 0;
                        } else if (integerWinding) {
                            w = sampler.windingAt(p);
                            in = w > 0;
                            ++evaluated;
                        } else {
                            in = sampler.inside(p);
                            ++evaluated;
                        }
                        if (integerWinding) winding[local] = static_cast<int8_t>(w);
                        v = in ? -d : d;
                        prev = d;
                        prevInside = in;
                        prevWinding = w;
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
    std::vector<float> blockSamples;
    assignHuge(blockSamples, kept.size() * perBlock, 0.0f);
    arena.execute([&] {
        tbb::parallel_for(size_t(0), kept.size(), [&](size_t n) {
            size_t b = kept[n];
            int bi = static_cast<int>(b % nb[0]), bj = static_cast<int>((b / nb[0]) % nb[1]),
                bk = static_cast<int>(b / (static_cast<size_t>(nb[0]) * nb[1]));
            float* out = blockSamples.data() + n * perBlock;
            for (int k = 0; k < V; ++k)
                for (int j = 0; j < V; ++j) {
                    // The first B vertices of a row lie in one owner (unless clamped at the end).
                    int i = 0;
                    if (bi * B + B <= s.cells[0]) {
                        const float* row = &owned[localIndex(bi * B, bj * B + j, bk * B + k)];
                        for (; i < B; ++i) *out++ = row[i];
                    }
                    for (; i < V; ++i) *out++ = vertex(bi * B + i, bj * B + j, bk * B + k);
                }
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

}  // namespace sdft
