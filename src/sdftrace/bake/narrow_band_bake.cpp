// The exact narrow-band bake (exact_bake.h: bakeExactSparse): triangles scattered to the vertices
// within the band of their bounds, surface blocks decided from unsigned distances, signs carried
// between neighbours (open meshes closed by films).
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <memory>

#include "exact_sampler.h"
#include "sdftrace/bake/closest_point.h"
#include "sdftrace/bake/exact_bake.h"
#include "sdftrace/bake/segment_crossing.h"
#include "sdftrace/bake/surface_seeds.h"
#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/exec/progress.h"
#include "sdftrace/exec/thread_arena.h"

namespace sdft {

using detail::report;
using detail::RowSampler;

Grid bakeExactSparse(const TriangleMesh& mesh, const GridShape& s, int B, float bandVoxels,
                     SignMethod sign, int threads, ExactBakeStats* stats, bool progress) {
    SDFT_CHECK(B == 4 || B == 8);
    // B is 4 or 8: shifts and masks instead of divisions in the per-vertex index arithmetic.
    const int shift = B == 4 ? 2 : 3, mask = B - 1;
    SDFT_CHECK(bandVoxels >= 2);
    std::vector<BakeStage> stages;
    StageClock phases(stages);
    // Parity signs cast rays; the winding number needs no BVH of the mesh.
    std::unique_ptr<MeshBvh> bvh =
        sign == SignMethod::RayParity ? std::make_unique<MeshBvh>(mesh) : nullptr;
    RowSampler sampler(mesh, bvh.get(), s, sign);
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
    std::atomic<size_t> queries{0}, signs{0}, filmSums{0};
    ThreadArena arena(threads);

    phases.mark("setup");
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
        // The owners whose vertices in the triangle's range come within `grow` of its plane (a
        // large triangle's grown bounds hold many owners far from it).
        auto forOwners = [&](size_t t, const VertexRange& r, auto&& f) {
            const auto& tri = mesh.triangles[t];
            const Vec3 a = mesh.positions[tri[0]];
            Vec3 n = cross(mesh.positions[tri[1]] - a, mesh.positions[tri[2]] - a);
            const float len = length(n);
            n = len > 0 ? n / len : Vec3(0.0f);
            const Vec3 an(std::fabs(n.x), std::fabs(n.y), std::fabs(n.z));
            const float limit = grow * 1.001f + 1e-6f * h;
            for (int ok = (r.lo[2] >> shift); ok <= (r.hi[2] >> shift); ++ok)
                for (int oj = (r.lo[1] >> shift); oj <= (r.hi[1] >> shift); ++oj)
                    for (int oi = (r.lo[0] >> shift); oi <= (r.hi[0] >> shift); ++oi) {
                        const Vec3 lo =
                            sampler.position(std::max(r.lo[0], oi * B), std::max(r.lo[1], oj * B),
                                             std::max(r.lo[2], ok * B));
                        const Vec3 hi = sampler.position(std::min(r.hi[0], oi * B + B - 1),
                                                         std::min(r.hi[1], oj * B + B - 1),
                                                         std::min(r.hi[2], ok * B + B - 1));
                        const Vec3 centre = (lo + hi) * 0.5f, half = (hi - lo) * 0.5f;
                        if (std::fabs(dot(centre - a, n)) - dot(half, an) > limit) continue;
                        f(ownerIndex(oi, oj, ok));
                    }
        };
        // In parallel: counts and slots by atomic increments. The order within a list varies
        // from run to run; its users do not depend on it (the distances sort their list, the
        // crossings sum theirs).
        arena.execute([&] {
            tbb::parallel_for(size_t(0), mesh.triangles.size(), [&](size_t t) {
                const auto& tri = mesh.triangles[t];
                const VertexRange& r = l.ranges[t] =
                    triangleVertexRange(s, mesh.positions[tri[0]], mesh.positions[tri[1]],
                                        mesh.positions[tri[2]], grow);
                if (r.empty()) return;
                forOwners(t, r, [&](size_t o) {
                    std::atomic_ref<uint32_t>(l.start[o + 1])
                        .fetch_add(1, std::memory_order_relaxed);
                });
            });
        });
        for (size_t o = 0; o < numOwners; ++o) l.start[o + 1] += l.start[o];
        assignHuge(l.items, l.start[numOwners], 0u);
        std::vector<uint32_t> fill(l.start.begin(), l.start.end() - 1);
        arena.execute([&] {
            tbb::parallel_for(size_t(0), mesh.triangles.size(), [&](size_t t) {
                const VertexRange& r = l.ranges[t];
                if (r.empty()) return;
                forOwners(t, r, [&](size_t o) {
                    uint32_t at =
                        std::atomic_ref<uint32_t>(fill[o]).fetch_add(1, std::memory_order_relaxed);
                    l.items[at] = static_cast<uint32_t>(t);
                });
            });
        });
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
    // Every owner's samples are written in 3 (first touched there, in parallel).
    const size_t ownedCount = static_cast<size_t>(owners) * perOwner;
    std::unique_ptr<float[]> owned = std::make_unique_for_overwrite<float[]>(ownedCount);
    adviseHugePages(owned.get(), ownedCount * sizeof(float));

    phases.mark("scatter");
    // Bit masks over the 8 blocks around an owner, d = dx + 2 dy + 4 dz for block (oi, oj, ok) -
    // (dx, dy, dz) or + (dx, dy, dz): subsetMask[z] holds the d whose axes are all in z (the axes
    // along which a vertex sits on the owner's first layer, so on the face it shares with them).
    static constexpr uint8_t subsetMask[8] = {0x01, 0x03, 0x05, 0x0F, 0x11, 0x33, 0x55, 0xFF};
    std::vector<uint8_t> nearBits(owners, 0);
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
                std::vector<std::pair<float, uint32_t>> order;
                for (int oi = 0; rowNeeded[row] && oi < no[0]; ++oi) {
                    size_t o = ownerIndex(oi, oj, ok);
                    int32_t sl = slot[o];
                    if (sl < 0) continue;
                    float* out = owned.get() + sl * perOwner;
                    std::fill(out, out + perOwner, reach);
                    const int i0 = oi * B, j0 = oj * B, k0 = ok * B;
                    // Nearest triangles first (by centroid): the bests shrink early and the
                    // bounds below then skip most of the others.
                    const Vec3 middle = sampler.position(i0, j0, k0) + Vec3(0.5f * (B - 1) * h);
                    order.clear();
                    for (uint32_t n = listStart[o]; n < listStart[o + 1]; ++n) {
                        const auto& tri = mesh.triangles[lists[n]];
                        Vec3 g = (mesh.positions[tri[0]] + mesh.positions[tri[1]] +
                                  mesh.positions[tri[2]]) /
                                     3.0f -
                                 middle;
                        order.emplace_back(dot(g, g), lists[n]);
                    }
                    std::sort(order.begin(), order.end());
                    for (const auto& [key, t] : order) {
                        const VertexRange& r = ranges[t];
                        const auto& tri = mesh.triangles[t];
                        Vec3 a = mesh.positions[tri[0]], b = mesh.positions[tri[1]],
                             c = mesh.positions[tri[2]];
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
                                    if (plane * plane * invN2 * 0.9999f > best * best) continue;
                                    float reachOut = best + radius;
                                    if (dot(p - centre, p - centre) * 0.9999f > reachOut * reachOut)
                                        continue;
                                    float d = length(p - closestPointOnTriangle(p, a, b, c));
                                    if (d < best) best = d;
                                }
                    }
                    // Which blocks this owner gives a sample within the band: bit d of nearBits
                    // for block (oi, oj, ok) - d's offsets, through the vertices on the faces
                    // those blocks share with it (only grid vertices count).
                    uint8_t bits = 0;
                    for (int lk = 0; lk < B && k0 + lk <= s.cells[2]; ++lk)
                        for (int lj = 0; lj < B && j0 + lj <= s.cells[1]; ++lj)
                            for (int li = 0; li < B && i0 + li <= s.cells[0]; ++li)
                                if (out[(lk * B + lj) * B + li] < reach) {
                                    bits |= subsetMask[(li == 0) | (lj == 0) << 1 | (lk == 0) << 2];
                                    ++found;
                                }
                    nearBits[sl] = bits;
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

    phases.mark("distances");
    // 4. Surface blocks: a (clamped, unsigned) sample within the band. A sign change needs the
    // surface between two vertices, hence one within half a cell diagonal: no other block holds
    // one. Only the vertices of surface blocks are signed one by one.
    const int V = B + 1;
    const size_t perBlock = static_cast<size_t>(V) * V * V;
    std::vector<uint8_t> keep;
    assignHuge(keep, numBlocks, uint8_t{0});
    auto localIndex = [&](int i, int j, int k) {
        i = std::min(i, s.cells[0]), j = std::min(j, s.cells[1]), k = std::min(k, s.cells[2]);
        return slot[ownerIndex((i >> shift), (j >> shift), (k >> shift))] * perOwner +
               (static_cast<size_t>((k & mask)) * B + (j & mask)) * B + (i & mask);
    };
    // Per owner: bit d set when block (oi, oj, ok) - d's offsets is a surface block. A vertex is
    // needed (signed one by one) when a surface block holds it.
    std::vector<uint8_t> heldBy(owners, 0);
    auto needed = [&](int32_t sl, int li, int lj, int lk) {
        return (heldBy[sl] & subsetMask[(li == 0) | (lj == 0) << 1 | (lk == 0) << 2]) != 0;
    };
    arena.execute([&] {
        // A candidate block is a surface block when one of its samples lies within the band.
        tbb::parallel_for(0, nb[2], [&](int bk) {
            for (int bj = 0; bj < nb[1]; ++bj)
                for (int bi = 0; bi < nb[0]; ++bi) {
                    const size_t b = blockIndex(bi, bj, bk);
                    if (!candidate[b]) continue;
                    bool near = false;
                    for (int d = 0; d < 8 && !near; ++d) {
                        int oi = bi + (d & 1), oj = bj + ((d >> 1) & 1), ok = bk + (d >> 2);
                        if (oi >= no[0] || oj >= no[1] || ok >= no[2]) continue;
                        int32_t sl = slot[ownerIndex(oi, oj, ok)];
                        near = sl >= 0 && (nearBits[sl] >> d & 1);
                    }
                    keep[b] = near;
                }
        });
        tbb::parallel_for(0, no[2], [&](int ok) {
            for (int oj = 0; oj < no[1]; ++oj)
                for (int oi = 0; oi < no[0]; ++oi) {
                    int32_t sl = slot[ownerIndex(oi, oj, ok)];
                    if (sl < 0) continue;
                    uint8_t bits = 0;
                    for (int d = 0; d < 8; ++d) {
                        int bi = oi - (d & 1), bj = oj - ((d >> 1) & 1), bk = ok - (d >> 2);
                        if (bi >= 0 && bj >= 0 && bk >= 0 && bi < nb[0] && bj < nb[1] &&
                            bk < nb[2] && keep[blockIndex(bi, bj, bk)])
                            bits |= static_cast<uint8_t>(1 << d);
                    }
                    heldBy[sl] = bits;
                }
        });
    });
    // The mesh's triangles prepared for crossing tests.
    const bool integerWinding = sampler.hasWinding();
    std::vector<CrossingTriangle> planes(integerWinding ? mesh.triangles.size() : 0);
    for (size_t t = 0; t < planes.size(); ++t) {
        const auto& tri = mesh.triangles[t];
        planes[t] = {mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]]};
    }
    // Triangles meeting a segment of length h that ends at a vertex come within h of it: the
    // crossing tests read lists grown by one voxel only.
    const OwnerLists nearLists = integerWinding ? binTriangles(1.01f * h) : OwnerLists{};
    auto crossings = [&](Vec3 a, Vec3 b, size_t o, int& delta) {
        const float eps = 1e-5f * h;
        for (uint32_t n = nearLists.start[o]; n < nearLists.start[o + 1]; ++n) {
            Crossing c = segmentCrossing(a, b, planes[nearLists.items[n]], eps);
            if (c == Crossing::Undecided) return false;
            delta += c == Crossing::Enter ? 1 : c == Crossing::Leave ? -1 : 0;
        }
        return true;
    };

    phases.mark("surface blocks");
    // 5. Signs of the surface blocks' vertices, one task per row of owners so that signs carry
    // along vertex rows. The winding numbers (closing_film.h) are carried from the previous
    // vertex of the row (or the -y / -z one at a chain start) through the signed crossings of
    // the segment between them: with the films, and with the mesh unless one of the two is
    // farther than a voxel from it. The mesh's own winding number is carried with an error that
    // grows by the step times the owner's gradient bound (0 on a watertight mesh), and summed
    // over the films again when that error reaches 1/2. They are evaluated from scratch only
    // where no neighbour can vouch. Parity signs carry only on a watertight mesh.
    using Carried = RowSampler::Carried;
    // The carried values of the current and the previous vertex layer, per task (the -y and -z
    // neighbours read them); read only where written (needed vertices of this slab).
    const size_t layer = static_cast<size_t>(nv[0]) * nv[1];
    tbb::enumerable_thread_specific<std::array<std::unique_ptr<Carried[]>, 2>> layers([&] {
        return std::array<std::unique_ptr<Carried[]>, 2>{
            integerWinding ? std::make_unique_for_overwrite<Carried[]>(layer) : nullptr,
            integerWinding ? std::make_unique_for_overwrite<Carried[]>(layer) : nullptr};
    });
    std::vector<float> gradient;
    // Per owner: W at its first vertex, for the blocks after a surface block in 6.
    std::vector<int32_t> cornerWinding(integerWinding ? owners : 0, 0);
    assignHuge(gradient, integerWinding ? static_cast<size_t>(owners) : 0, 0.0f);
    if (integerWinding && !sampler.watertight()) {
        // Per owner: the gradient bound over its vertices and their -x, -y, -z neighbours.
        arena.execute([&] {
            tbb::parallel_for(0, no[2], [&](int ok) {
                for (int oj = 0; oj < no[1]; ++oj)
                    for (int oi = 0; oi < no[0]; ++oi) {
                        int32_t sl = slot[ownerIndex(oi, oj, ok)];
                        if (sl < 0) continue;
                        gradient[sl] = sampler.gradientBound(
                            sampler.position(oi * B - 1, oj * B - 1, ok * B - 1),
                            sampler.position(oi * B + B, oj * B + B, ok * B + B));
                    }
            });
        });
    }
    arena.execute([&] {
        // One task per slab of owners (B vertex layers in z): within it every vertex's -y and -z
        // neighbours are signed before it.
        tbb::parallel_for(0, no[2], [&](int ok) {
            size_t evaluated = 0, refreshed = 0;
            auto& buffers = layers.local();
            // Per row of owners: the films that its segments may cross.
            std::vector<uint32_t> films;
            int filmRow = -1;
            for (int k = ok * B; k < std::min(ok * B + B, nv[2]); ++k)
                for (int j = 0; j < nv[1]; ++j) {
                    const int oj = j >> shift;
                    if (!rowNeeded[static_cast<size_t>(ok) * no[1] + oj]) {
                        j = oj * B + B - 1;
                        continue;
                    }
                    Carried* const layerNow = buffers[k & 1].get();
                    const Carried* const layerBefore = buffers[(k - 1) & 1].get();
                    if (integerWinding && filmRow != oj) {
                        filmRow = oj;
                        sampler.filmsNear(sampler.position(0, oj * B - 1, ok * B - 1),
                                          sampler.position(nv[0], oj * B + B, ok * B + B), films);
                    }
                    float prev = -1;
                    bool prevInside = false;
                    Carried prevCarried;
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
                        if (!needed(sl, i & mask, j & mask, k & mask)) {
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
                        Carried nCarried = prevCarried;
                        Vec3 np = sampler.position(i - 1, j, k);
                        auto vouch = [&](int ni, int nj, int nk) {
                            int32_t ns = slot[ownerIndex(ni >> shift, nj >> shift, nk >> shift)];
                            if (ns < 0) return false;
                            size_t nl =
                                ns * perOwner + ((nk & mask) * B + (nj & mask)) * B + (ni & mask);
                            if (!needed(ns, ni & mask, nj & mask, nk & mask)) return false;
                            nd = std::fabs(owned[nl]);
                            nInside = owned[nl] < 0;
                            if (integerWinding)
                                nCarried =
                                    (nk == k ? layerNow
                                             : layerBefore)[static_cast<size_t>(nj) * nv[0] + ni];
                            np = sampler.position(ni, nj, nk);
                            return true;
                        };
                        if ((watertight || integerWinding) && !have)
                            have =
                                (j > 0 && vouch(i, j - 1, k)) || (k > ok * B && vouch(i, j, k - 1));
                        bool in;
                        Carried c;
                        const bool meshClear = have && (d > step || nd > step);
                        if (integerWinding) {
                            int meshDelta = 0, filmDelta = 0;
                            if (have && (meshClear || crossings(np, p, o, meshDelta)) &&
                                sampler.filmCrossings(np, p, films, filmDelta)) {
                                c = sampler.carry(nCarried, meshDelta + filmDelta, meshDelta,
                                                  gradient[sl] * h, p, refreshed);
                            } else {
                                c = sampler.evaluate(p);
                                ++evaluated;
                            }
                            in = c.inside();
                        } else if (watertight && meshClear) {
                            in = nInside;
                        } else {
                            in = sampler.inside(p);
                            ++evaluated;
                        }
                        if (integerWinding) {
                            layerNow[static_cast<size_t>(j) * nv[0] + i] = c;
                            if (((i | j | k) & mask) == 0) cornerWinding[sl] = c.closed;
                        }
                        v = in ? -d : d;
                        prev = d;
                        prevInside = in;
                        prevCarried = c;
                    }
                }
            signs += evaluated;
            filmSums += refreshed;
        });
    });

    phases.mark("signs");
    // 6. The other blocks take the sign at their centre: carried from the previous block's in the
    // row when that one was not a surface block either (neither holds surface, and the segment
    // between the centres stays in them), the winding number with an error grown as in 5.
    std::atomic<size_t> centreSigns{0};
    arena.execute([&] {
        tbb::parallel_for(0, nb[1] * nb[2], [&](int row) {
            const int bj = row % nb[1], bk = row / nb[1];
            bool prevFree = false, prevInside = false;
            Carried prevCarried;
            Vec3 prevCentre;
            size_t evaluated = 0, refreshed = 0;
            auto centre = [&](int bi) {
                Vec3 lo = sampler.position(bi * B, bj * B, bk * B);
                Vec3 hi = sampler.position(std::min(bi * B + B, s.cells[0]),
                                           std::min(bj * B + B, s.cells[1]),
                                           std::min(bk * B + B, s.cells[2]));
                return (lo + hi) * 0.5f;
            };
            std::vector<uint32_t> films;
            if (integerWinding)
                sampler.filmsNear(sampler.position(0, bj * B, bk * B), centre(nb[0] - 1), films);
            // One gradient bound for the whole row where the rim is far from it (most rows).
            const float rowGradient =
                integerWinding ? sampler.gradientBound(centre(0), centre(nb[0] - 1)) : 0.0f;
            const bool rowBounded = rowGradient * B * h < 1e-3f;
            for (int bi = 0; bi < nb[0]; ++bi) {
                size_t b = blockIndex(bi, bj, bk);
                if (keep[b]) {
                    flags[b] = static_cast<uint8_t>(BlockFlag::Surface);
                    prevFree = false;
                    continue;
                }
                const Vec3 c = centre(bi);
                bool in = prevInside;
                // After a surface block: its vertex at this block's first corner was signed, and
                // the segment from it to the centre stays in this block.
                int32_t corner = -1;
                if (!prevFree && bi > 0) {
                    corner = slot[ownerIndex(bi, bj, bk)];
                    const Vec3 q = sampler.position(bi * B, bj * B, bk * B);
                    int delta = 0;
                    if (corner >= 0 && integerWinding &&
                        sampler.filmCrossings(q, c, films, delta)) {
                        prevCarried = {cornerWinding[corner] + delta, 0, 0};
                    } else if (corner >= 0 && watertight && !integerWinding) {
                        prevInside = owned[corner * perOwner] < 0;
                    } else {
                        corner = -1;
                    }
                }
                if (integerWinding) {
                    Carried w;
                    int delta = 0;
                    if (corner >= 0) {
                        w = sampler.refresh(c, prevCarried.closed);
                        refreshed += !sampler.watertight();
                    } else if (prevFree && sampler.filmCrossings(prevCentre, c, films, delta)) {
                        float grad = rowBounded ? rowGradient
                                                : sampler.gradientBound(min(prevCentre, c),
                                                                        max(prevCentre, c));
                        w = sampler.carry(prevCarried, delta, 0, grad * length(c - prevCentre), c,
                                          refreshed);
                    } else {
                        w = sampler.evaluate(c);
                        ++evaluated;
                    }
                    in = w.inside();
                    prevCarried = w;
                } else if (corner >= 0) {
                    in = prevInside;
                } else if (!(watertight && prevFree)) {
                    in = sampler.inside(c);
                    ++evaluated;
                }
                flags[b] = static_cast<uint8_t>(in ? BlockFlag::Inside : BlockFlag::Outside);
                prevFree = true;
                prevInside = in;
                prevCentre = c;
            }
            centreSigns += evaluated;
            filmSums += refreshed;
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
    phases.mark("other blocks and gather");
    report(stats, queries, signs, filmSums);
    if (stats) stats->surfaceBlocks = kept.size();
    Grid grid;
    arena.execute([&] {
        grid = Grid::sparseFromBuffers(s, B, (bandVoxels - 1) * h, std::move(flags),
                                       std::move(blockSamples), "exact bake");
    });
    phases.mark("grid");  // cell masks and the Lipschitz bound
    if (stats) stats->phases = std::move(stages);
    return grid;
}

}  // namespace sdft
