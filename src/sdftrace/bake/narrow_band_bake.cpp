// The exact narrow-band bake (exact_bake.h: bakeExactSparse) as one object whose phases run in
// order: triangles scattered to the owner blocks within the band of their bounds (scatter), exact
// unsigned distances at those owners' vertices (distances), surface blocks decided from them
// (surfaceBlocks), signs carried between neighbouring vertices with open meshes closed by films
// (signs), one sign per other block (otherBlocks), and the sparse grid assembled (gather).
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstring>
#include <memory>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "exact_sampler.h"
#include "sdftrace/bake/closest_point.h"
#include "sdftrace/bake/exact_bake.h"
#include "sdftrace/bake/exact_slab.h"
#include "sdftrace/bake/segment_crossing.h"
#include "sdftrace/bake/surface_seeds.h"
#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/exec/progress.h"
#include "sdftrace/exec/thread_arena.h"
#include "sdftrace/field/block_apron_layout.h"
#include "sdftrace/field/sparse_grid_builder.h"

namespace sdft {

using detail::report;
using detail::RowSampler;

namespace {

// Bit masks over the 8 blocks around an owner, d = dx + 2 dy + 4 dz for block (oi, oj, ok) -
// (dx, dy, dz) or + (dx, dy, dz): kSubsetMask[z] holds the d whose axes are all in z (the axes
// along which a vertex sits on the owner's first layer, so on the face it shares with them).
constexpr uint8_t kSubsetMask[8] = {0x01, 0x03, 0x05, 0x0F, 0x11, 0x33, 0x55, 0xFF};

uint8_t subsetMask(int li, int lj, int lk) {
    return kSubsetMask[(li == 0) | (lj == 0) << 1 | (lk == 0) << 2];
}

// Per owner block (or per needed owner's slot), the triangles whose bounds grown by some distance
// overlap its vertices (a prefix-summed list).
struct OwnerLists {
    std::vector<uint32_t> start, items;
};

class NarrowBandBake {
  public:
    NarrowBandBake(const TriangleMesh& mesh, const GridShape& s, int B, float bandVoxels,
                   SignMethod sign, int threads, bool progress, BlockSlab slab = {});

    Grid run(ExactBakeStats* stats);
    // The slab's blocks only (bakeExactSlab).
    SlabSamples runSlab(ExactBakeStats* stats);
    // The same as a .sdfg's sections (bakeExactSlabSections).
    SlabSections runSlabSections(const NextLayerFlags& nextLayer, ExactBakeStats* stats);

  private:
    using Carried = RowSampler::Carried;

    // The phases, in order.
    void scatter();
    void distances();
    void surfaceBlocks();
    void signs();
    void otherBlocks();
    void phases();
    Grid gather(ExactBakeStats* stats);
    void keptBlocks();
    void blockSamples(size_t b, float* out) const;
    void splitBlock(size_t b, const std::vector<uint8_t>& next, float* own, uint64_t* mask,
                    std::vector<float>* kept) const;

    // Blocks and owners are stored for the window of z layers a slab needs (the whole grid
    // without slabs): index arithmetic takes global layers.
    size_t blockIndex(int bi, int bj, int bk) const {
        return (static_cast<size_t>(bk - m_b0) * m_nb[1] + bj) * m_nb[0] + bi;
    }
    // Vertex v belongs to owner (v >> shift); one more owner layer holds the last vertices of each
    // axis.
    size_t ownerIndex(int oi, int oj, int ok) const {
        return (static_cast<size_t>(ok - m_o0) * m_no[1] + oj) * m_no[0] + oi;
    }
    size_t rowIndex(int oj, int ok) const { return static_cast<size_t>(ok - m_o0) * m_no[1] + oj; }
    // Index into m_owned of vertex (i, j, k), clamped to the grid.
    size_t localIndex(int i, int j, int k) const {
        i = std::min(i, m_s.cells[0]), j = std::min(j, m_s.cells[1]), k = std::min(k, m_s.cells[2]);
        return m_slot[ownerIndex(i >> m_shift, j >> m_shift, k >> m_shift)] * m_perOwner +
               (static_cast<size_t>(k & m_mask) * m_B + (j & m_mask)) * m_B + (i & m_mask);
    }
    // Whether the vertex at local (li, lj, lk) of owner slot `sl` is held by a surface block.
    bool needed(int32_t sl, int li, int lj, int lk) const {
        return (m_heldBy[sl] & subsetMask(li, lj, lk)) != 0;
    }

    OwnerLists binTriangles(float grow, bool bySlot);
    template <class F>
    void forOwnersNearPlane(size_t t, const VertexRange& r, float grow, F&& f) const;
    void markCandidates();
    void dropUnheldOwners();
    void dilateOwners(std::vector<uint8_t>& v, int dir) const;
    size_t ownerDistances(int oi, int oj, int ok, std::vector<std::pair<float, uint32_t>>& order);
    void nearestToTriangle(Vec3 a, Vec3 b, Vec3 c, const int lo[3], const int hi[3], int i0, int j0,
                           int k0, float* out) const;
    bool crossings(Vec3 a, Vec3 b, size_t slot, int& delta) const;
    void ownerGradients();
    struct SlabSigns;
    void signVertexRow(int ok, int k, int j, SlabSigns& slab);
    void signBlockRow(int row, size_t& evaluated, size_t& refreshed);

    const TriangleMesh& m_mesh;
    const GridShape& m_s;
    const int m_B, m_shift, m_mask;
    const float m_bandVoxels, m_h, m_reach;
    float m_slack = 0;  // absolute rounding allowance of the distance bounds (nearestToTriangle)
    const bool m_progress;
    std::vector<BakeStage> m_stages;
    StageClock m_phases;
    ThreadArena m_arena;
    // Parity signs cast rays; the winding number needs no BVH of the mesh.
    std::unique_ptr<MeshBvh> m_bvh;
    RowSampler m_sampler;
    const bool m_watertight, m_integerWinding;
    int m_nv[3], m_nb[3], m_no[3];
    // The slab's block layers [m_z0, m_z1) (its output), and the windows of block layers
    // [m_b0, m_b1) and owner layers [m_o0, m_o1) whose arrays it keeps: one layer more on each
    // side, which is what the slab's results read (runSlab).
    int m_z0 = 0, m_z1 = 0, m_b0 = 0, m_b1 = 0, m_o0 = 0, m_o1 = 0;
    size_t m_numBlocks, m_numOwners;
    size_t m_perOwner;
    std::atomic<size_t> m_queries{0}, m_signs{0}, m_filmSums{0};

    OwnerLists m_band;                        // lists grown by the band (scatter)
    OwnerLists m_near;                        // grown by a voxel (crossing tests)
    std::vector<uint8_t> m_flags;             // BlockFlag per block
    std::vector<uint8_t> m_candidate;         // may hold surface: an owner lists a triangle
    std::vector<uint8_t> m_keep;              // surface blocks (the candidates' array, then)
    std::vector<int32_t> m_slot;              // per owner: its slot in m_owned, -1 if not needed
    std::vector<uint8_t> m_rowNeeded;         // per row of owners: any needed
    int32_t m_owners = 0;                     // needed owners
    std::unique_ptr<float[]> m_owned;         // per needed owner, B^3 samples
    std::vector<uint8_t> m_nearBits;          // per owner: blocks it gives a sample within the band
    std::vector<uint8_t> m_heldBy;            // per owner: surface blocks that hold its vertices
    std::vector<float> m_gradient;            // per owner: the winding number's gradient bound
    std::vector<int32_t> m_cornerWinding;     // per owner: W at its first vertex
    std::vector<size_t> m_kept;               // surface block indices, in order
    std::vector<std::array<int, 3>> m_apron;  // the apron's vertices (runSlabSections)
};

NarrowBandBake::NarrowBandBake(const TriangleMesh& mesh, const GridShape& s, int B,
                               float bandVoxels, SignMethod sign, int threads, bool progress,
                               BlockSlab slab)
    : m_mesh(mesh),
      m_s(s),
      m_B(B),
      m_shift(B == 4 ? 2 : 3),
      m_mask(B - 1),
      m_bandVoxels(bandVoxels),
      m_h(s.voxelSize),
      m_reach(bandVoxels * s.voxelSize),
      m_progress(progress),
      m_phases(m_stages),
      m_arena(threads),
      m_bvh(sign == SignMethod::RayParity ? std::make_unique<MeshBvh>(mesh) : nullptr),
      m_sampler(mesh, m_bvh.get(), s, sign, /*deferSigns=*/true),
      m_watertight(m_sampler.watertight()),
      m_integerWinding(m_sampler.hasWinding()) {
    // B is 4 or 8: shifts and masks instead of divisions in the per-vertex index arithmetic.
    SDFT_CHECK(B == 4 || B == 8);
    SDFT_CHECK(bandVoxels >= 2);
    for (int a = 0; a < 3; ++a) {
        m_nv[a] = s.vertices(a);
        m_nb[a] = (s.cells[a] + B - 1) / B;
        m_no[a] = (s.cells[a] >> m_shift) + 1;
    }
    m_z0 = std::clamp(slab.first, 0, m_nb[2]);
    m_z1 = slab.last > 0 ? std::clamp(slab.last, m_z0, m_nb[2]) : m_nb[2];
    m_b0 = m_o0 = std::max(0, m_z0 - 1);
    m_b1 = std::min(m_nb[2], m_z1 + 1);
    m_o1 = std::min(m_no[2], m_z1 + 2);
    m_numBlocks = static_cast<size_t>(m_nb[0]) * m_nb[1] * (m_b1 - m_b0);
    m_numOwners = static_cast<size_t>(m_no[0]) * m_no[1] * (m_o1 - m_o0);
    m_perOwner = static_cast<size_t>(B) * B * B;
    float scale = 0;
    for (int a = 0; a < 3; ++a)
        scale = std::max(scale, std::fabs(s.origin[a]) + std::fabs(s.origin[a] + s.cells[a] * m_h));
    for (const Vec3& p : mesh.positions)
        scale = std::max(scale, std::max(std::fabs(p.x), std::max(std::fabs(p.y), std::fabs(p.z))));
    m_slack = 1e-6f * scale;
}

Grid NarrowBandBake::run(ExactBakeStats* stats) {
    phases();
    return gather(stats);
}

void NarrowBandBake::phases() {
    m_phases.mark("setup");
    scatter();
    m_phases.mark("scatter");
    distances();
    m_phases.mark("distances");
    m_band = OwnerLists();  // each phase frees what no later one reads: the peak is lower
    surfaceBlocks();
    m_phases.mark("surface blocks");
    signs();
    m_phases.mark("signs");
    otherBlocks();
    m_near = OwnerLists();
    m_gradient = std::vector<float>();
    m_sampler.releaseSigns();
}

// The owners whose vertices in the triangle's range come within `grow` of its plane (a large
// triangle's grown bounds hold many owners far from it).
template <class F>
void NarrowBandBake::forOwnersNearPlane(size_t t, const VertexRange& r, float grow, F&& f) const {
    const int B = m_B, shift = m_shift;
    const auto& tri = m_mesh.triangles[t];
    const Vec3 a = m_mesh.positions[tri[0]];
    Vec3 n = cross(m_mesh.positions[tri[1]] - a, m_mesh.positions[tri[2]] - a);
    const float len = length(n);
    n = len > 0 ? n / len : Vec3(0.0f);
    const Vec3 an(std::fabs(n.x), std::fabs(n.y), std::fabs(n.z));
    const float limit = grow * 1.001f + 1e-6f * m_h;
    for (int ok = std::max(m_o0, r.lo[2] >> shift); ok <= std::min(m_o1 - 1, r.hi[2] >> shift);
         ++ok)
        for (int oj = (r.lo[1] >> shift); oj <= (r.hi[1] >> shift); ++oj)
            for (int oi = (r.lo[0] >> shift); oi <= (r.hi[0] >> shift); ++oi) {
                const Vec3 lo =
                    m_sampler.position(std::max(r.lo[0], oi * B), std::max(r.lo[1], oj * B),
                                       std::max(r.lo[2], ok * B));
                const Vec3 hi = m_sampler.position(std::min(r.hi[0], oi * B + B - 1),
                                                   std::min(r.hi[1], oj * B + B - 1),
                                                   std::min(r.hi[2], ok * B + B - 1));
                const Vec3 centre = (lo + hi) * 0.5f, half = (hi - lo) * 0.5f;
                if (std::fabs(dot(centre - a, n)) - dot(half, an) > limit) continue;
                f(ownerIndex(oi, oj, ok));
            }
}

// bySlot: lists for the needed owners only, indexed by their slots (the crossing tests, once the
// slots are known: a dense table over the window's owners is 60 MB per rank at 2048 cells).
OwnerLists NarrowBandBake::binTriangles(float grow, bool bySlot) {
    const TriangleMesh& mesh = m_mesh;
    OwnerLists l;
    const size_t lists = bySlot ? static_cast<size_t>(m_owners) : m_numOwners;
    assignHuge(l.start, lists + 1, 0u);
    // Each triangle's vertex range, computed in both passes rather than stored.
    const auto range = [&](size_t t) {
        const auto& tri = mesh.triangles[t];
        return triangleVertexRange(m_s, mesh.positions[tri[0]], mesh.positions[tri[1]],
                                   mesh.positions[tri[2]], grow);
    };
    const auto forLists = [&](size_t t, const VertexRange& r, auto&& f) {
        forOwnersNearPlane(t, r, grow, [&](size_t o) {
            if (!bySlot) return f(o);
            if (const int32_t sl = m_slot[o]; sl >= 0) f(static_cast<size_t>(sl));
        });
    };
    // In parallel: counts and slots by atomic increments. The order within a list varies from run
    // to run; its users do not depend on it (the distances sort their list, the crossings sum
    // theirs).
    m_arena.execute([&] {
        tbb::parallel_for(size_t(0), mesh.triangles.size(), [&](size_t t) {
            const VertexRange r = range(t);
            if (r.empty()) return;
            forLists(t, r, [&](size_t o) {
                std::atomic_ref<uint32_t>(l.start[o + 1]).fetch_add(1, std::memory_order_relaxed);
            });
        });
    });
    for (size_t o = 0; o < lists; ++o) l.start[o + 1] += l.start[o];
    assignHuge(l.items, l.start[lists], 0u);
    m_arena.execute([&] {
        tbb::parallel_for(size_t(0), mesh.triangles.size(), [&](size_t t) {
            const VertexRange r = range(t);
            if (r.empty()) return;
            forLists(t, r, [&](size_t o) {
                uint32_t at =
                    std::atomic_ref<uint32_t>(l.start[o]).fetch_add(1, std::memory_order_relaxed);
                l.items[at] = static_cast<uint32_t>(t);
            });
        });
    });
    // The starts served as cursors and now hold the ends, that is the next list's start: one
    // place back (no copy of the starts, 240 MB at 2048 cells).
    std::memmove(l.start.data() + 1, l.start.data(), lists * sizeof(uint32_t));
    l.start[0] = 0;
    return l;
}

// 1. Scatter: a vertex closer than the band to the mesh is within the band of its closest
// triangle's bounds, so each owner block lists the triangles whose bounds, grown by the band,
// overlap its vertices; the minimum over them is exact there. Vertices farther away are clamped to
// the band (as a narrow-band level set stores them). Then the candidate blocks and the owners
// they need (markCandidates).
void NarrowBandBake::scatter() {
    m_band = binTriangles(m_reach, false);
    markCandidates();
}

// 2. Blocks none of whose owners list a triangle hold no vertex within the band, hence no surface
// (it would pass within half a cell diagonal of a vertex): one sign for the block. The others are
// candidates, and need all 8 of their owners.
void NarrowBandBake::markCandidates() {
    const int* nb = m_nb;
    const int* no = m_no;
    assignHuge(m_flags, m_numBlocks, static_cast<uint8_t>(BlockFlag::Outside));
    assignHuge(m_candidate, m_numBlocks, uint8_t{0});
    assignHuge(m_slot, m_numOwners, -1);
    m_rowNeeded.assign(static_cast<size_t>(no[1]) * (m_o1 - m_o0), 0);
    // Both relations are 2x2x2 box dilations over the owner lattice (blocks index a part of it),
    // done one axis at a time in one byte per owner.
    std::vector<uint8_t> mark;
    assignHuge(mark, m_numOwners, uint8_t{0});
    m_arena.execute([&] {
        tbb::parallel_for(size_t(0), m_numOwners,
                          [&](size_t o) { mark[o] = m_band.start[o + 1] > m_band.start[o]; });
        dilateOwners(mark, +1);
        tbb::parallel_for(m_b0, m_b1, [&](int bk) {
            for (int bj = 0; bj < nb[1]; ++bj)
                std::copy_n(&mark[ownerIndex(0, bj, bk)], nb[0],
                            &m_candidate[blockIndex(0, bj, bk)]);
        });
        // An owner is needed by the candidates among the (up to 8) blocks that use its vertices.
        tbb::parallel_for(m_o0, m_o1, [&](int ok) {
            for (int oj = 0; oj < no[1]; ++oj) {
                uint8_t* row = &mark[ownerIndex(0, oj, ok)];
                std::fill_n(row, no[0], uint8_t{0});
                if (oj < nb[1] && ok < m_b1)
                    std::copy_n(&m_candidate[blockIndex(0, oj, ok)], nb[0], row);
            }
        });
        dilateOwners(mark, -1);
        tbb::parallel_for(m_o0, m_o1, [&](int ok) {
            for (int oj = 0; oj < no[1]; ++oj) {
                const size_t first = ownerIndex(0, oj, ok);
                uint8_t row = 0;
                for (int oi = 0; oi < no[0]; ++oi) {
                    if (mark[first + oi]) m_slot[first + oi] = 0;
                    row |= mark[first + oi];
                }
                m_rowNeeded[rowIndex(oj, ok)] = row;
            }
        });
    });
    for (int32_t& sl : m_slot)
        if (sl == 0) sl = m_owners++;
    // Every owner's samples are written in 3 (first touched there, in parallel).
    const size_t ownedCount = static_cast<size_t>(m_owners) * m_perOwner;
    m_owned = std::make_unique_for_overwrite<float[]>(ownedCount);
    adviseHugePages(m_owned.get(), ownedCount * sizeof(float));
}

// In place over the owner lattice, one axis after the other: v[o] |= v[o + dir] along x, y and
// z (dir = +1 or -1), so that v[o] ends as the OR over the 2x2x2 box from o towards dir.
void NarrowBandBake::dilateOwners(std::vector<uint8_t>& v, int dir) const {
    const int* no = m_no;
    const int nz = m_o1 - m_o0;  // the window's layers
    const size_t sy = static_cast<size_t>(no[0]), sz = sy * no[1];
    // base[i * stride + w] |= base[(i + dir) * stride + w] for w < width, over i in the order that
    // reads each neighbour before it changes (ascending for +1, descending for -1).
    auto orAlong = [dir](uint8_t* base, int n, size_t stride, size_t width) {
        for (int step = 0; step + 1 < n; ++step) {
            const size_t i = static_cast<size_t>(dir > 0 ? step : n - 1 - step);
            uint8_t* to = base + i * stride;
            const uint8_t* from = to + dir * static_cast<std::ptrdiff_t>(stride);
            for (size_t w = 0; w < width; ++w) to[w] |= from[w];
        }
    };
    tbb::parallel_for(0, no[1] * nz, [&](int row) {
        orAlong(v.data() + static_cast<size_t>(row) * sy, no[0], 1, 1);
    });
    tbb::parallel_for(0, nz, [&](int lk) { orAlong(v.data() + lk * sz, no[1], sy, sy); });
    tbb::parallel_for(0, no[1], [&](int oj) { orAlong(v.data() + oj * sy, nz, sz, sy); });
}

// 3. Distances, one task per row of owners.
void NarrowBandBake::distances() {
    m_nearBits.assign(m_owners, 0);
    Progress bar("sdftrace bake: narrow band", static_cast<uint64_t>(m_no[1]) * (m_o1 - m_o0),
                 m_progress && stderrIsTerminal());
    m_arena.execute([&] {
        tbb::parallel_for(0, m_no[1] * (m_o1 - m_o0), [&](int row) {
            const int oj = row % m_no[1], ok = m_o0 + row / m_no[1];
            size_t found = 0;
            std::vector<std::pair<float, uint32_t>> order;
            for (int oi = 0; m_rowNeeded[row] && oi < m_no[0]; ++oi)
                found += ownerDistances(oi, oj, ok, order);
            m_queries += found;
            bar.advance();
        });
    });
}

// The exact distances (clamped to the band) of one owner's vertices, nearest triangles first;
// returns how many lie within the band.
size_t NarrowBandBake::ownerDistances(int oi, int oj, int ok,
                                      std::vector<std::pair<float, uint32_t>>& order) {
    const TriangleMesh& mesh = m_mesh;
    const int B = m_B;
    const float h = m_h;
    const size_t o = ownerIndex(oi, oj, ok);
    const int32_t sl = m_slot[o];
    if (sl < 0) return 0;
    float* out = m_owned.get() + sl * m_perOwner;
    std::fill(out, out + m_perOwner, m_reach);
    const int i0 = oi * B, j0 = oj * B, k0 = ok * B;
    // Nearest triangles first (by centroid): the bests shrink early and the bounds below then
    // skip most of the others.
    const Vec3 middle = m_sampler.position(i0, j0, k0) + Vec3(0.5f * (B - 1) * h);
    order.clear();
    for (uint32_t n = m_band.start[o]; n < m_band.start[o + 1]; ++n) {
        const auto& tri = mesh.triangles[m_band.items[n]];
        Vec3 g = (mesh.positions[tri[0]] + mesh.positions[tri[1]] + mesh.positions[tri[2]]) / 3.0f -
                 middle;
        order.emplace_back(dot(g, g), m_band.items[n]);
    }
    std::sort(order.begin(), order.end());
    for (const auto& [key, t] : order) {
        const auto& tri = mesh.triangles[t];
        const Vec3 a = mesh.positions[tri[0]], b = mesh.positions[tri[1]],
                   c = mesh.positions[tri[2]];
        // The triangle's vertex range again rather than a stored copy (26 MB for a million
        // triangles on every rank of a distributed bake, most of them outside its slab).
        const VertexRange r = triangleVertexRange(m_s, a, b, c, m_reach);
        const int lo[3] = {std::max(i0, r.lo[0]), std::max(j0, r.lo[1]), std::max(k0, r.lo[2])};
        const int hi[3] = {std::min(i0 + B - 1, r.hi[0]), std::min(j0 + B - 1, r.hi[1]),
                           std::min(k0 + B - 1, r.hi[2])};
        nearestToTriangle(a, b, c, lo, hi, i0, j0, k0, out);
    }
    // Which blocks this owner gives a sample within the band: bit d of nearBits for block
    // (oi, oj, ok) - d's offsets, through the vertices on the faces those blocks share with it
    // (only grid vertices count).
    uint8_t bits = 0;
    size_t found = 0;
    for (int lk = 0; lk < B && k0 + lk <= m_s.cells[2]; ++lk)
        for (int lj = 0; lj < B && j0 + lj <= m_s.cells[1]; ++lj)
            for (int li = 0; li < B && i0 + li <= m_s.cells[0]; ++li)
                if (out[(lk * B + lj) * B + li] < m_reach) {
                    bits |= subsetMask(li, lj, lk);
                    ++found;
                }
    m_nearBits[sl] = bits;
    return found;
}

// Lowers the best distances of the owner's vertices in [lo, hi] (out: the owner's B^3 samples,
// (i0, j0, k0) its first vertex) to the triangle abc's. Two lower bounds skip a vertex before the
// exact closest point: its distance to the triangle's plane, and to the disk in that plane that
// holds the triangle (centred on its centroid). Both are conservative: they give up a relative
// 1e-4 and an absolute m_slack, the rounding of coordinates far larger than the distances (at
// 2048 cells a vertex 0.4 voxels from the surface is 4e-4 from it at coordinates near 1, where
// float spacing is 1e-7), so no triangle that could lower a best is skipped.
void NarrowBandBake::nearestToTriangle(Vec3 a, Vec3 b, Vec3 c, const int lo[3], const int hi[3],
                                       int i0, int j0, int k0, float* out) const {
    const int B = m_B;
    const Vec3 nrm = cross(b - a, c - a);
    const float invN2 = 1.0f / std::fmax(dot(nrm, nrm), 1e-37f);
    const Vec3 centre = (a + b + c) / 3.0f;
    const float radius =
        std::sqrt(std::fmax(dot(a - centre, a - centre),
                            std::fmax(dot(b - centre, b - centre), dot(c - centre, c - centre))));
    auto exact = [&](int i, int j, int k) {
        const Vec3 p = m_sampler.position(i, j, k);
        float& best = out[((k - k0) * B + (j - j0)) * B + (i - i0)];
        const float d = length(p - closestPointOnTriangle(p, a, b, c));
        if (d < best) best = d;
    };
    const float slack = m_slack, r1 = radius * 1.0001f;
#if defined(__SSE2__)
    // A row of 4 vertices along x is one vector (B = 8: two); both bounds on all four, then the
    // exact distance for those that pass.
    const Vec3 origin = m_sampler.position(0, 0, 0);
    const float h = m_h;
    const __m128 lane = _mm_setr_ps(0, 1, 2, 3), zero = _mm_setzero_ps();
    for (int c0 = i0; c0 < i0 + B; c0 += 4) {
        if (c0 + 3 < lo[0] || c0 > hi[0]) continue;
        const __m128 fi = _mm_add_ps(_mm_set1_ps(static_cast<float>(c0)), lane);
        const __m128 valid = _mm_and_ps(_mm_cmpge_ps(fi, _mm_set1_ps(static_cast<float>(lo[0]))),
                                        _mm_cmple_ps(fi, _mm_set1_ps(static_cast<float>(hi[0]))));
        const __m128 x = _mm_add_ps(_mm_set1_ps(origin.x), _mm_mul_ps(fi, _mm_set1_ps(h)));
        const __m128 planeX = _mm_mul_ps(_mm_sub_ps(x, _mm_set1_ps(a.x)), _mm_set1_ps(nrm.x));
        const __m128 dcx = _mm_sub_ps(x, _mm_set1_ps(centre.x));
        const __m128 dcx2 = _mm_mul_ps(dcx, dcx);
        for (int k = lo[2]; k <= hi[2]; ++k) {
            const float z = origin.z + static_cast<float>(k) * h;
            for (int j = lo[1]; j <= hi[1]; ++j) {
                const float y = origin.y + static_cast<float>(j) * h;
                float* row = out + ((k - k0) * B + (j - j0)) * B + (c0 - i0);
                const __m128 reach = _mm_add_ps(_mm_loadu_ps(row), _mm_set1_ps(slack));
                const __m128 reach2 = _mm_mul_ps(reach, reach);
                const __m128 plane =
                    _mm_add_ps(planeX, _mm_set1_ps((y - a.y) * nrm.y + (z - a.z) * nrm.z));
                const __m128 h2 = _mm_mul_ps(_mm_mul_ps(plane, plane), _mm_set1_ps(invN2));
                const __m128 farPlane = _mm_cmpgt_ps(_mm_mul_ps(h2, _mm_set1_ps(0.9999f)), reach2);
                const float dy = y - centre.y, dz = z - centre.z;
                const __m128 d2 = _mm_add_ps(dcx2, _mm_set1_ps(dy * dy + dz * dz));
                const __m128 tol = _mm_add_ps(_mm_mul_ps(d2, _mm_set1_ps(4e-5f)),
                                              _mm_set1_ps(4e-5f * radius * radius));
                const __m128 rho =
                    _mm_sqrt_ps(_mm_max_ps(_mm_sub_ps(_mm_sub_ps(d2, h2), tol), zero));
                const __m128 e = _mm_max_ps(_mm_sub_ps(rho, _mm_set1_ps(r1)), zero);
                const __m128 farDisk =
                    _mm_cmpgt_ps(_mm_sub_ps(_mm_add_ps(h2, _mm_mul_ps(e, e)), tol), reach2);
                int m = _mm_movemask_ps(_mm_andnot_ps(_mm_or_ps(farPlane, farDisk), valid));
                while (m) {
                    exact(c0 + std::countr_zero(static_cast<unsigned>(m)), j, k);
                    m &= m - 1;
                }
            }
        }
    }
#else
    for (int k = lo[2]; k <= hi[2]; ++k)
        for (int j = lo[1]; j <= hi[1]; ++j)
            for (int i = lo[0]; i <= hi[0]; ++i) {
                const Vec3 p = m_sampler.position(i, j, k);
                const float reach = out[((k - k0) * B + (j - j0)) * B + (i - i0)] + slack;
                const float plane = dot(p - a, nrm), h2 = plane * plane * invN2;
                if (h2 * 0.9999f > reach * reach) continue;
                const float d2 = dot(p - centre, p - centre);
                const float tol = 4e-5f * d2 + 4e-5f * radius * radius;
                const float e = std::max(std::sqrt(std::max(d2 - h2 - tol, 0.0f)) - r1, 0.0f);
                if (h2 + e * e - tol > reach * reach) continue;
                exact(i, j, k);
            }
#endif
}

// 4. Surface blocks: a (clamped, unsigned) sample within the band. A sign change needs the surface
// between two vertices, hence one within half a cell diagonal: no other block holds one. Only the
// vertices of surface blocks are signed one by one.
void NarrowBandBake::surfaceBlocks() {
    const int* nb = m_nb;
    const int* no = m_no;
    m_keep = std::move(m_candidate);  // a candidate stays when it is a surface block
    // Per owner: bit d set when block (oi, oj, ok) - d's offsets is a surface block. A vertex is
    // needed (signed one by one) when a surface block holds it.
    m_heldBy.assign(m_owners, 0);
    m_arena.execute([&] {
        // A candidate block is a surface block when one of its samples lies within the band.
        tbb::parallel_for(m_b0, m_b1, [&](int bk) {
            for (int bj = 0; bj < nb[1]; ++bj)
                for (int bi = 0; bi < nb[0]; ++bi) {
                    const size_t b = blockIndex(bi, bj, bk);
                    if (!m_keep[b]) continue;
                    bool near = false;
                    for (int d = 0; d < 8 && !near; ++d) {
                        int oi = bi + (d & 1), oj = bj + ((d >> 1) & 1), ok = bk + (d >> 2);
                        if (oi >= no[0] || oj >= no[1] || ok >= m_o1) continue;
                        int32_t sl = m_slot[ownerIndex(oi, oj, ok)];
                        near = sl >= 0 && (m_nearBits[sl] >> d & 1);
                    }
                    m_keep[b] = near;
                }
        });
        tbb::parallel_for(m_o0, m_o1, [&](int ok) {
            for (int oj = 0; oj < no[1]; ++oj)
                for (int oi = 0; oi < no[0]; ++oi) {
                    int32_t sl = m_slot[ownerIndex(oi, oj, ok)];
                    if (sl < 0) continue;
                    uint8_t bits = 0;
                    for (int d = 0; d < 8; ++d) {
                        int bi = oi - (d & 1), bj = oj - ((d >> 1) & 1), bk = ok - (d >> 2);
                        if (bi >= 0 && bj >= 0 && bk >= m_b0 && bi < nb[0] && bj < nb[1] &&
                            bk < m_b1 && m_keep[blockIndex(bi, bj, bk)])
                            bits |= static_cast<uint8_t>(1 << d);
                    }
                    m_heldBy[sl] = bits;
                }
        });
    });
    dropUnheldOwners();
    // Triangles meeting a segment of length h that ends at a vertex come within h of it: the
    // crossing tests read lists grown by one voxel only.
    if (m_integerWinding) {
        m_near = binTriangles(1.01f * m_h, true);
    }
}

// Owners that no surface block holds are not read again (their vertices are neither signed nor
// gathered; the sign walks treat them as owners without samples): the others slide down in order,
// their slots renumbered, and the freed tail of the samples goes back to the system (a quarter to
// a third of the owners, 200 MB at 2048 cells on the rock).
void NarrowBandBake::dropUnheldOwners() {
    std::vector<int32_t> renumbered(static_cast<size_t>(m_owners), -1);
    int32_t kept = 0;
    for (int32_t sl = 0; sl < m_owners; ++sl)
        if (m_heldBy[sl]) renumbered[sl] = kept++;
    m_nearBits = std::vector<uint8_t>();
    if (kept == m_owners) return;
    // In order: a slot only moves down, onto one already moved or dropped.
    for (int32_t sl = 0; sl < m_owners; ++sl) {
        const int32_t to = renumbered[sl];
        if (to < 0 || to == sl) continue;
        std::memcpy(m_owned.get() + to * m_perOwner, m_owned.get() + sl * m_perOwner,
                    m_perOwner * sizeof(float));
        m_heldBy[to] = m_heldBy[sl];
    }
    m_arena.execute([&] {
        tbb::parallel_for(size_t(0), m_numOwners, [&](size_t o) {
            if (m_slot[o] >= 0) m_slot[o] = renumbered[m_slot[o]];
        });
    });
    m_heldBy.resize(kept);
    releasePages(m_owned.get() + kept * m_perOwner, (m_owners - kept) * m_perOwner * sizeof(float));
    m_owners = kept;
}

// The signed crossings of segment ab with the mesh's triangles listed near the owner in slot sl;
// false when one is too close to call. The triangles' planes are not stored (a million-triangle
// mesh's take 80 MB at the bake's peak): those whose bounds meet the segment are prepared here.
bool NarrowBandBake::crossings(Vec3 a, Vec3 b, size_t sl, int& delta) const {
    const float eps = 1e-5f * m_h;
    const auto& pos = m_mesh.positions;
    for (uint32_t n = m_near.start[sl]; n < m_near.start[sl + 1]; ++n) {
        const auto& tri = m_mesh.triangles[m_near.items[n]];
        const Vec3 ta = pos[tri[0]], tb = pos[tri[1]], tc = pos[tri[2]];
        if (segmentMissesBox(a, b, min(ta, min(tb, tc)), max(ta, max(tb, tc)), eps)) continue;
        Crossing c = segmentCrossing(a, b, CrossingTriangle(ta, tb, tc), eps);
        if (c == Crossing::Undecided) return false;
        delta += c == Crossing::Enter ? 1 : c == Crossing::Leave ? -1 : 0;
    }
    return true;
}

// Per owner: the winding number's gradient bound over its vertices and their -x, -y, -z
// neighbours (open meshes only).
void NarrowBandBake::ownerGradients() {
    const int B = m_B;
    assignHuge(m_gradient, m_integerWinding ? static_cast<size_t>(m_owners) : 0, 0.0f);
    if (!m_integerWinding || m_watertight) return;
    m_arena.execute([&] {
        tbb::parallel_for(m_o0, m_o1, [&](int ok) {
            for (int oj = 0; oj < m_no[1]; ++oj)
                for (int oi = 0; oi < m_no[0]; ++oi) {
                    int32_t sl = m_slot[ownerIndex(oi, oj, ok)];
                    if (sl < 0) continue;
                    m_gradient[sl] = m_sampler.gradientBound(
                        m_sampler.position(oi * B - 1, oj * B - 1, ok * B - 1),
                        m_sampler.position(oi * B + B, oj * B + B, ok * B + B));
                }
        });
    });
}

// What one task (a slab of owners, B vertex layers in z) carries from row to row.
struct NarrowBandBake::SlabSigns {
    // The carried values of the current and the previous vertex layer (the -y and -z neighbours
    // read them); read only where written (needed vertices of this slab).
    std::array<std::unique_ptr<Carried[]>, 2>* layers = nullptr;
    std::vector<uint32_t> films;  // the films the current row of owners' segments may cross
    int filmRow = -1;
    size_t evaluated = 0, refreshed = 0;
};

// 5. Signs of the surface blocks' vertices, one task per slab of owners so that signs carry along
// vertex rows: within it every vertex's -y and -z neighbours are signed before it. The winding
// numbers (closing_film.h) are carried from the previous vertex of the row (or the -y / -z one at
// a chain start) through the signed crossings of the segment between them: with the films, and
// with the mesh unless one of the two is farther than a voxel from it. The mesh's own winding
// number is carried with an error that grows by the step times the owner's gradient bound (0 on a
// watertight mesh), and summed over the films again when that error reaches 1/2. They are
// evaluated from scratch only where no neighbour can vouch. Parity signs carry only on a
// watertight mesh.
void NarrowBandBake::signs() {
    const size_t layer = static_cast<size_t>(m_nv[0]) * m_nv[1];
    tbb::enumerable_thread_specific<std::array<std::unique_ptr<Carried[]>, 2>> layers([&] {
        return std::array<std::unique_ptr<Carried[]>, 2>{
            m_integerWinding ? std::make_unique_for_overwrite<Carried[]>(layer) : nullptr,
            m_integerWinding ? std::make_unique_for_overwrite<Carried[]>(layer) : nullptr};
    });
    m_arena.execute([&] { m_sampler.prepareSigns(); });
    m_phases.mark("winding tree");
    m_cornerWinding.assign(m_integerWinding ? m_owners : 0, 0);
    ownerGradients();
    m_arena.execute([&] {
        // The slab's owner layers: those its blocks' vertices lie in.
        tbb::parallel_for(m_z0, std::min(m_z1 + 1, m_o1), [&](int ok) {
            SlabSigns slab;
            slab.layers = &layers.local();
            for (int k = ok * m_B; k < std::min(ok * m_B + m_B, m_nv[2]); ++k)
                for (int j = 0; j < m_nv[1]; ++j) {
                    const int oj = j >> m_shift;
                    if (!m_rowNeeded[rowIndex(oj, ok)]) {
                        j = oj * m_B + m_B - 1;
                        continue;
                    }
                    signVertexRow(ok, k, j, slab);
                }
            m_signs += slab.evaluated;
            m_filmSums += slab.refreshed;
        });
    });
}

// The needed vertices of row (j, k) in slab ok, in order of i.
void NarrowBandBake::signVertexRow(int ok, int k, int j, SlabSigns& slab) {
    const int B = m_B, shift = m_shift, mask = m_mask;
    const int oj = j >> shift;
    const int* nv = m_nv;
    const float step = m_h * 1.001f;
    Carried* const layerNow = (*slab.layers)[k & 1].get();
    const Carried* const layerBefore = (*slab.layers)[(k - 1) & 1].get();
    if (m_integerWinding && slab.filmRow != oj) {
        slab.filmRow = oj;
        m_sampler.filmsNear(m_sampler.position(0, oj * B - 1, ok * B - 1),
                            m_sampler.position(nv[0], oj * B + B, ok * B + B), slab.films);
    }
    float prev = -1;
    bool prevInside = false;
    Carried prevCarried;
    for (int i = 0; i < nv[0]; ++i) {
        const size_t o = ownerIndex((i >> shift), oj, ok);
        int32_t sl = m_slot[o];
        if (sl < 0) {
            i = ((i >> shift)) * B + B - 1;  // skip the owner; the chain breaks
            prev = -1;
            continue;
        }
        const size_t local = sl * m_perOwner + (((k & mask)) * B + ((j & mask))) * B + ((i & mask));
        if (!needed(sl, i & mask, j & mask, k & mask)) {
            prev = -1;
            continue;
        }
        float& v = m_owned[local];
        const float d = v;
        const Vec3 p = m_sampler.position(i, j, k);
        // The vouching neighbour: the previous vertex of the chain, else the signed -y one, else
        // the -z one in this slab.
        bool have = prev >= 0;
        float nd = prev;
        bool nInside = prevInside;
        Carried nCarried = prevCarried;
        Vec3 np = m_sampler.position(i - 1, j, k);
        auto vouch = [&](int ni, int nj, int nk) {
            int32_t ns = m_slot[ownerIndex(ni >> shift, nj >> shift, nk >> shift)];
            if (ns < 0) return false;
            size_t nl = ns * m_perOwner + ((nk & mask) * B + (nj & mask)) * B + (ni & mask);
            if (!needed(ns, ni & mask, nj & mask, nk & mask)) return false;
            nd = std::fabs(m_owned[nl]);
            nInside = m_owned[nl] < 0;
            if (m_integerWinding)
                nCarried = (nk == k ? layerNow : layerBefore)[static_cast<size_t>(nj) * nv[0] + ni];
            np = m_sampler.position(ni, nj, nk);
            return true;
        };
        if ((m_watertight || m_integerWinding) && !have)
            have = (j > 0 && vouch(i, j - 1, k)) || (k > ok * B && vouch(i, j, k - 1));
        bool in;
        Carried c;
        const bool meshClear = have && (d > step || nd > step);
        if (m_integerWinding) {
            int meshDelta = 0, filmDelta = 0;
            if (have && (meshClear || crossings(np, p, static_cast<size_t>(sl), meshDelta)) &&
                m_sampler.filmCrossings(np, p, slab.films, filmDelta)) {
                c = m_sampler.carry(nCarried, meshDelta + filmDelta, meshDelta,
                                    m_gradient[sl] * m_h, p, slab.refreshed);
            } else {
                c = m_sampler.evaluate(p);
                ++slab.evaluated;
            }
            in = c.inside();
        } else if (m_watertight && meshClear) {
            in = nInside;
        } else {
            in = m_sampler.inside(p);
            ++slab.evaluated;
        }
        if (m_integerWinding) {
            layerNow[static_cast<size_t>(j) * nv[0] + i] = c;
            if (((i | j | k) & mask) == 0) m_cornerWinding[sl] = c.closed;
        }
        v = in ? -d : d;
        prev = d;
        prevInside = in;
        prevCarried = c;
    }
}

// 6. The other blocks take the sign at their centre: carried from the previous block's in the row
// when that one was not a surface block either (neither holds surface, and the segment between the
// centres stays in them), the winding number with an error grown as in 5.
void NarrowBandBake::otherBlocks() {
    std::atomic<size_t> centreSigns{0};
    m_arena.execute([&] {
        tbb::parallel_for(0, m_nb[1] * (m_z1 - m_z0), [&](int row) {
            size_t evaluated = 0, refreshed = 0;
            signBlockRow(row, evaluated, refreshed);
            centreSigns += evaluated;
            m_filmSums += refreshed;
        });
    });
    m_signs += centreSigns.load();
}

void NarrowBandBake::signBlockRow(int row, size_t& evaluated, size_t& refreshed) {
    const int B = m_B;
    const int bj = row % m_nb[1], bk = m_z0 + row / m_nb[1];
    bool prevFree = false, prevInside = false;
    Carried prevCarried;
    Vec3 prevCentre;
    auto centre = [&](int bi) {
        Vec3 lo = m_sampler.position(bi * B, bj * B, bk * B);
        Vec3 hi = m_sampler.position(std::min(bi * B + B, m_s.cells[0]),
                                     std::min(bj * B + B, m_s.cells[1]),
                                     std::min(bk * B + B, m_s.cells[2]));
        return (lo + hi) * 0.5f;
    };
    std::vector<uint32_t> films;
    if (m_integerWinding)
        m_sampler.filmsNear(m_sampler.position(0, bj * B, bk * B), centre(m_nb[0] - 1), films);
    // One gradient bound for the whole row where the rim is far from it (most rows).
    const float rowGradient =
        m_integerWinding ? m_sampler.gradientBound(centre(0), centre(m_nb[0] - 1)) : 0.0f;
    const bool rowBounded = rowGradient * B * m_h < 1e-3f;
    for (int bi = 0; bi < m_nb[0]; ++bi) {
        size_t b = blockIndex(bi, bj, bk);
        if (m_keep[b]) {
            m_flags[b] = static_cast<uint8_t>(BlockFlag::Surface);
            prevFree = false;
            continue;
        }
        const Vec3 c = centre(bi);
        bool in = prevInside;
        // After a surface block: its vertex at this block's first corner was signed, and the
        // segment from it to the centre stays in this block.
        int32_t corner = -1;
        if (!prevFree && bi > 0) {
            corner = m_slot[ownerIndex(bi, bj, bk)];
            const Vec3 q = m_sampler.position(bi * B, bj * B, bk * B);
            int delta = 0;
            if (corner >= 0 && m_integerWinding && m_sampler.filmCrossings(q, c, films, delta)) {
                prevCarried = {m_cornerWinding[corner] + delta, 0, 0};
            } else if (corner >= 0 && m_watertight && !m_integerWinding) {
                prevInside = m_owned[corner * m_perOwner] < 0;
            } else {
                corner = -1;
            }
        }
        if (m_integerWinding) {
            Carried w;
            int delta = 0;
            if (corner >= 0) {
                w = m_sampler.refresh(c, prevCarried.closed);
                refreshed += !m_watertight;
            } else if (prevFree && m_sampler.filmCrossings(prevCentre, c, films, delta)) {
                float grad = rowBounded
                                 ? rowGradient
                                 : m_sampler.gradientBound(min(prevCentre, c), max(prevCentre, c));
                w = m_sampler.carry(prevCarried, delta, 0, grad * length(c - prevCentre), c,
                                    refreshed);
            } else {
                w = m_sampler.evaluate(c);
                ++evaluated;
            }
            in = w.inside();
            prevCarried = w;
        } else if (corner >= 0) {
            in = prevInside;
        } else if (!(m_watertight && prevFree)) {
            in = m_sampler.inside(c);
            ++evaluated;
        }
        m_flags[b] = static_cast<uint8_t>(in ? BlockFlag::Inside : BlockFlag::Outside);
        prevFree = true;
        prevInside = in;
        prevCentre = c;
    }
}

// The surface blocks of the slab's layers, in flat block order.
void NarrowBandBake::keptBlocks() {
    const size_t layer = static_cast<size_t>(m_nb[0]) * m_nb[1];
    for (size_t b = (m_z0 - m_b0) * layer; b < (m_z1 - m_b0) * layer; ++b)
        if (m_keep[b]) m_kept.push_back(b);
    m_keep = std::vector<uint8_t>();
}

// Block b's (B+1)^3 vertex samples, x fastest, out of the owners.
void NarrowBandBake::blockSamples(size_t b, float* out) const {
    const int B = m_B, V = B + 1;
    const int bi = static_cast<int>(b % m_nb[0]), bj = static_cast<int>((b / m_nb[0]) % m_nb[1]),
              bk = m_b0 + static_cast<int>(b / (static_cast<size_t>(m_nb[0]) * m_nb[1]));
    for (int k = 0; k < V; ++k)
        for (int j = 0; j < V; ++j) {
            // The first B vertices of a row lie in one owner (unless clamped at the end).
            int i = 0;
            if (bi * B + B <= m_s.cells[0]) {
                const float* row = &m_owned[localIndex(bi * B, bj * B + j, bk * B + k)];
                for (; i < B; ++i) *out++ = row[i];
            }
            for (; i < V; ++i) *out++ = m_owned[localIndex(bi * B + i, bj * B + j, bk * B + k)];
        }
}

// The surface blocks' samples copied out of the owners, and the sparse grid.
Grid NarrowBandBake::gather(ExactBakeStats* stats) {
    SDFT_CHECK(m_z0 == 0 && m_z1 == m_nb[2]);  // the whole grid (slabs: runSlab)
    keptBlocks();
    // Straight into the grid's compact layout (the owners' samples are one value per vertex).
    SparseGridBuilder builder(m_s, m_B, (m_bandVoxels - 1) * m_h,
                              BlockTable::fromDense(m_nb, m_flags, "exact bake"), "exact bake");
    m_flags = std::vector<uint8_t>();
    m_arena.execute([&] {
        tbb::parallel_for(size_t(0), m_kept.size(), [&](size_t n) {
            const size_t b = m_kept[n];
            float block[9 * 9 * 9];  // (B+1)^3, B <= 8
            blockSamples(b, block);
            const int bi = static_cast<int>(b % m_nb[0]),
                      bj = static_cast<int>((b / m_nb[0]) % m_nb[1]),
                      bk = static_cast<int>(b / (static_cast<size_t>(m_nb[0]) * m_nb[1]));
            builder.addBlock(bi, bj, bk, block);
        });
    });
    m_owned.reset();
    m_phases.mark("other blocks and gather");
    report(stats, m_queries, m_signs, m_filmSums);
    if (stats) stats->surfaceBlocks = m_kept.size();
    Grid grid;
    m_arena.execute([&] { grid = builder.finish(); });
    m_phases.mark("grid");  // cell masks and the Lipschitz bound
    if (stats) stats->phases = std::move(m_stages);
    return grid;
}

SlabSamples NarrowBandBake::runSlab(ExactBakeStats* stats) {
    phases();
    keptBlocks();
    SlabSamples out;
    out.slab = {m_z0, m_z1};
    const size_t layer = static_cast<size_t>(m_nb[0]) * m_nb[1];
    out.flags.assign(m_flags.begin() + (m_z0 - m_b0) * layer,
                     m_flags.begin() + (m_z1 - m_b0) * layer);
    m_flags = std::vector<uint8_t>();
    const size_t perBlock = static_cast<size_t>(m_B + 1) * (m_B + 1) * (m_B + 1);
    assignHuge(out.samples, m_kept.size() * perBlock, 0.0f);
    m_arena.execute([&] {
        tbb::parallel_for(size_t(0), m_kept.size(), [&](size_t n) {
            blockSamples(m_kept[n], out.samples.data() + n * perBlock);
        });
    });
    m_owned.reset();
    m_phases.mark("other blocks and gather");
    report(stats, m_queries, m_signs, m_filmSums);
    if (stats) {
        stats->surfaceBlocks = m_kept.size();
        stats->phases = std::move(m_stages);
    }
    return out;
}

// Block b's own samples and apron mask (and its kept apron samples, if `kept`), as the version-4
// writer splits the assembled grid's (block_aprons.h: splitAprons): an apron vertex is implicit
// where the block that owns it is a surface block, which then holds the same value (the samples
// are one value per vertex). `next`: the flags of the layer past the slab.
void NarrowBandBake::splitBlock(size_t b, const std::vector<uint8_t>& next, float* own,
                                uint64_t* mask, std::vector<float>* kept) const {
    const int B = m_B, V = B + 1;
    const size_t layer = static_cast<size_t>(m_nb[0]) * m_nb[1];
    const int at[3] = {static_cast<int>(b % m_nb[0]), static_cast<int>((b / m_nb[0]) % m_nb[1]),
                       m_b0 + static_cast<int>(b / layer)};
    float block[9 * 9 * 9];  // (B+1)^3, B <= 8
    blockSamples(b, block);
    for (int k = 0; k < B; ++k)
        for (int j = 0; j < B; ++j)
            for (int i = 0; i < B; ++i) *own++ = block[(k * V + j) * V + i];
    bool surface[8] = {false};  // per neighbour entry: its owner holds samples
    for (int code = 1; code < 8; ++code) {
        int o[3];
        if (!neighbourBlock(at, code, m_nb, o)) continue;
        const uint8_t f = o[2] < m_z1 ? m_flags[blockIndex(o[0], o[1], o[2])]
                                      : next.at((static_cast<size_t>(o[1]) * m_nb[0]) + o[0]);
        surface[code] = f == static_cast<uint8_t>(BlockFlag::Surface);
    }
    int a = 0;
    for (const auto& p : m_apron) {
        const int code = (p[0] == B) | (p[1] == B) << 1 | (p[2] == B) << 2;
        if (!surface[code]) {
            mask[a / 64] |= uint64_t{1} << (a % 64);
            if (kept) kept->push_back(block[(p[2] * V + p[1]) * V + p[0]]);
        }
        ++a;
    }
}

SlabSections NarrowBandBake::runSlabSections(const NextLayerFlags& nextLayer,
                                             ExactBakeStats* stats) {
    phases();
    keptBlocks();
    SlabSections out;
    out.slab = {m_z0, m_z1};
    const size_t layer = static_cast<size_t>(m_nb[0]) * m_nb[1];
    std::vector<uint8_t> first;
    if (m_z1 > m_z0)
        first.assign(m_flags.begin() + (m_z0 - m_b0) * layer,
                     m_flags.begin() + (m_z0 - m_b0 + 1) * layer);
    const std::vector<uint8_t> next = nextLayer(first);
    if (m_z1 < m_nb[2] && next.size() != layer)
        throw std::runtime_error("exact bake: the next slab's first layer has the wrong size");
    m_apron = apronPositions(m_B);
    const size_t perOwn = static_cast<size_t>(m_B) * m_B * m_B;
    const int words = apronWords(m_B);
    out.surfaceBlocks = m_kept.size();
    assignHuge(out.own, m_kept.size() * perOwn, 0.0f);
    out.apronMasks.assign(m_kept.size() * words, 0);
    // The kept samples by pieces of blocks in parallel, joined in block order.
    constexpr size_t kPiece = 4096;
    std::vector<std::vector<float>> pieces((m_kept.size() + kPiece - 1) / kPiece);
    m_arena.execute([&] {
        tbb::parallel_for(size_t(0), pieces.size(), [&](size_t piece) {
            const size_t end = std::min(m_kept.size(), (piece + 1) * kPiece);
            for (size_t n = piece * kPiece; n < end; ++n)
                splitBlock(m_kept[n], next, out.own.data() + n * perOwn,
                           out.apronMasks.data() + n * words, &pieces[piece]);
        });
    });
    size_t total = 0;
    for (const auto& p : pieces) total += p.size();
    out.kept.reserve(total);
    for (auto& p : pieces) {
        out.kept.insert(out.kept.end(), p.begin(), p.end());
        p = std::vector<float>();
    }
    out.flags.assign(m_flags.begin() + (m_z0 - m_b0) * layer,
                     m_flags.begin() + (m_z1 - m_b0) * layer);
    m_flags = std::vector<uint8_t>();
    m_owned.reset();
    m_phases.mark("other blocks and sections");
    report(stats, m_queries, m_signs, m_filmSums);
    if (stats) {
        stats->surfaceBlocks = m_kept.size();
        stats->phases = std::move(m_stages);
    }
    return out;
}

}  // namespace

Grid bakeExactSparse(const TriangleMesh& mesh, const GridShape& s, int B, float bandVoxels,
                     SignMethod sign, int threads, ExactBakeStats* stats, bool progress) {
    return NarrowBandBake(mesh, s, B, bandVoxels, sign, threads, progress).run(stats);
}

}  // namespace sdft

namespace sdft {

SlabSamples bakeExactSlab(const TriangleMesh& mesh, const GridShape& shape, int blockSize,
                          float bandVoxels, SignMethod sign, BlockSlab slab, int threads,
                          ExactBakeStats* stats, bool progress) {
    return NarrowBandBake(mesh, shape, blockSize, bandVoxels, sign, threads, progress, slab)
        .runSlab(stats);
}

SlabSections bakeExactSlabSections(const TriangleMesh& mesh, const GridShape& shape, int blockSize,
                                   float bandVoxels, SignMethod sign, BlockSlab slab,
                                   const NextLayerFlags& nextLayer, int threads,
                                   ExactBakeStats* stats, bool progress) {
    return NarrowBandBake(mesh, shape, blockSize, bandVoxels, sign, threads, progress, slab)
        .runSlabSections(nextLayer, stats);
}

Grid assembleExactSlabs(const GridShape& shape, int blockSize, float bandVoxels,
                        const std::vector<const SlabSamples*>& slabs, int threads) {
    const int B = blockSize;
    int nb[3];
    for (int a = 0; a < 3; ++a) nb[a] = (shape.cells[a] + B - 1) / B;
    const size_t layer = static_cast<size_t>(nb[0]) * nb[1];
    std::vector<uint8_t> flags;
    assignHuge(flags, layer * nb[2], static_cast<uint8_t>(BlockFlag::Outside));
    int covered = 0;
    for (const SlabSamples* s : slabs) {
        if (s->slab.first != covered || s->flags.size() != layer * (s->slab.last - s->slab.first))
            throw std::runtime_error("exact bake: slabs do not cover the grid in order");
        std::copy(s->flags.begin(), s->flags.end(), flags.begin() + covered * layer);
        covered = s->slab.last;
    }
    if (covered != nb[2]) throw std::runtime_error("exact bake: slabs do not cover the grid");
    SparseGridBuilder builder(shape, B, (bandVoxels - 1) * shape.voxelSize,
                              BlockTable::fromDense(nb, flags, "exact bake"), "exact bake");
    flags = std::vector<uint8_t>();
    const size_t perBlock = static_cast<size_t>(B + 1) * (B + 1) * (B + 1);
    ThreadArena arena(threads);
    Grid grid;
    arena.execute([&] {
        for (const SlabSamples* s : slabs) {
            // The slab's surface blocks, in flat order, numbered as its samples are.
            std::vector<size_t> blocks;
            for (size_t b = 0; b < s->flags.size(); ++b)
                if (s->flags[b] == static_cast<uint8_t>(BlockFlag::Surface)) blocks.push_back(b);
            if (blocks.size() * perBlock != s->samples.size())
                throw std::runtime_error("exact bake: a slab's samples do not match its blocks");
            tbb::parallel_for(size_t(0), blocks.size(), [&](size_t n) {
                const size_t b = blocks[n];
                builder.addBlock(static_cast<int>(b % nb[0]), static_cast<int>((b / nb[0]) % nb[1]),
                                 s->slab.first + static_cast<int>(b / layer),
                                 s->samples.data() + n * perBlock);
            });
        }
        grid = builder.finish();
    });
    return grid;
}

}  // namespace sdft
