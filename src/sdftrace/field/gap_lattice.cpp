// The gap lattice of a sparse narrow band (Grid::computeGapLattice): a lower bound of the distance
// to the reconstruction's zero set at the vertices of a lattice of step s cells.
//
// A narrow band (Jamriška 2010, §3) clamps its samples to +-band and drops the blocks beyond, so
// what sphere tracing and SDF soft shadows (Tan et al. 2022, §2.4) read within a block or so of the
// surface is the band's width, not the distance. The zero set of the trilinear reconstruction lies
// in the cells whose corner samples change sign (the cell masks, Jamriška §4.1), hence in the
// union of the step-s cells (s^3 cells each) holding one. The point of such a box nearest to a
// lattice vertex v is one of the box's corners (per axis, an integer clamped to [i, i + 1] stays
// an integer), so E(v), the exact Euclidean distance from v to the nearest corner of those boxes
// (Felzenszwalb and Huttenlocher 2012's separable transform, three passes of lower envelopes of
// parabolas), is v's distance to their union: at most its distance to the zero set. It is kept
// in eighths of a step, rounded down, in a byte: beyond 31 7/8 steps the block gaps take over.
// gridDistanceBound (grid_distance.h) carries it to any point p through the distance's
// 1-Lipschitz bound, from the best of the 8 corners of p's lattice cell.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <vector>

#include "sdftrace/field/grid.h"
#include "sdftrace/field/lower_envelope.h"

namespace sdft {

namespace {

constexpr float kFar = std::numeric_limits<float>::infinity();

// One pass of the transform along `axis` of the n[0] x n[1] x n[2] array d (x fastest), lines in
// parallel.
void distancePass(std::vector<float>& d, const int n[3], int axis) {
    const size_t stride = axis == 0   ? 1
                          : axis == 1 ? static_cast<size_t>(n[0])
                                      : static_cast<size_t>(n[0]) * n[1];
    const int len = n[axis];
    const int a = axis == 0 ? 1 : 0, b = axis == 2 ? 1 : 2;  // the other two axes
    const size_t lines = static_cast<size_t>(n[a]) * n[b];
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, lines), [&](const tbb::blocked_range<size_t>& r) {
            std::vector<int> v(static_cast<size_t>(len));
            std::vector<float> z(static_cast<size_t>(len) + 1), line(static_cast<size_t>(len)),
                out(static_cast<size_t>(len));
            for (size_t l = r.begin(); l != r.end(); ++l) {
                int c[3] = {0, 0, 0};
                c[a] = static_cast<int>(l % static_cast<size_t>(n[a]));
                c[b] = static_cast<int>(l / static_cast<size_t>(n[a]));
                const size_t base =
                    (static_cast<size_t>(c[2]) * n[1] + static_cast<size_t>(c[1])) * n[0] +
                    static_cast<size_t>(c[0]);
                for (int i = 0; i < len; ++i) line[static_cast<size_t>(i)] = d[base + i * stride];
                lowerEnvelope(len, line.data(), out.data(), nullptr, v.data(), z.data());
                for (int i = 0; i < len; ++i) d[base + i * stride] = out[static_cast<size_t>(i)];
            }
        });
}

}  // namespace

void Grid::computeGapLattice(size_t maxVertices) {
    m_gapLattice.clear();
    m_gapStep = 1;
    if (m_kind != GridKind::Sparse || m_complete || m_surfaceBlocks == 0) return;
    if (maxVertices == 0)
        maxVertices =
            std::clamp<size_t>(memoryBytes() / 4, size_t(33) * 33 * 33, size_t(129) * 129 * 129);
    int s = 1, n[3];
    auto fit = [&] {
        for (int a = 0; a < 3; ++a) n[a] = (m_shape.cells[a] + s - 1) / s + 1;
        return static_cast<size_t>(n[0]) * n[1] * n[2] <= maxVertices;
    };
    while (!fit()) ++s;
    std::vector<float> d(static_cast<size_t>(n[0]) * n[1] * n[2], kFar);
    // The seeds: the corners of each step-s cell holding a cell with a sign change.
    const int B = m_blockSize, words = (B * B * B + 63) / 64;
    std::atomic<bool> any{false};
    auto seed = [&](int x, int y, int z) {  // the corners of step-s cell (x, y, z)
        for (int corner = 0; corner < 8; ++corner) {
            const size_t at = (static_cast<size_t>(z + (corner >> 2)) * n[1] +
                               static_cast<size_t>(y + (corner >> 1 & 1))) *
                                  n[0] +
                              static_cast<size_t>(x + (corner & 1));
            std::atomic_ref<float>(d[at]).store(0.0f, std::memory_order_relaxed);
        }
    };
    // A block meets at most `span` step-s cells per axis. Up to 4, the ones its crossings touch
    // are gathered row by row of the cell mask (B bits of x each) in a 64-bit set first, so that
    // each is seeded once and no bit is visited alone; beyond (s = 1 at B = 8), cell by cell.
    const int span = (B + s - 1) / s + 1;
    forEachPagedBlock([&](int bi, int bj, int bk, size_t slot) {
        const int32_t data = m_blockData[slot];
        if (data < 0) return;
        const uint64_t* mask = m_cellMasks.data() + static_cast<size_t>(data) * words;
        const int first[3] = {bi * B / s, bj * B / s, bk * B / s};
        if (span > 4) {
            for (int w = 0; w < words; ++w)
                for (uint64_t bits = mask[w]; bits; bits &= bits - 1) {
                    const int bit = w * 64 + std::countr_zero(bits);
                    seed((bi * B + bit % B) / s, (bj * B + (bit / B) % B) / s,
                         (bk * B + bit / (B * B)) / s);
                    any.store(true, std::memory_order_relaxed);
                }
            return;
        }
        uint32_t columns[4] = {0, 0, 0, 0};  // per step-s cell of x: its local x bits
        for (int x = 0; x < B; ++x) columns[(bi * B + x) / s - first[0]] |= 1u << x;
        uint64_t touched = 0;
        for (int k = 0; k < B; ++k)
            for (int j = 0; j < B; ++j) {
                const int row = (k * B + j) * B;
                const uint32_t r =
                    static_cast<uint32_t>(mask[row / 64] >> (row % 64)) & ((1u << B) - 1);
                if (!r) continue;
                const int yz =
                    4 * ((bj * B + j) / s - first[1]) + 16 * ((bk * B + k) / s - first[2]);
                for (int t = 0; t < span; ++t)
                    if (r & columns[t]) touched |= uint64_t(1) << (t + yz);
            }
        if (touched) any.store(true, std::memory_order_relaxed);
        for (; touched; touched &= touched - 1) {
            const int t = std::countr_zero(touched);
            seed(first[0] + (t & 3), first[1] + (t >> 2 & 3), first[2] + (t >> 4));
        }
    });
    if (!any.load()) return;
    for (int axis = 0; axis < 3; ++axis) distancePass(d, n, axis);
    // Eighths of a step, rounded down (a lower bound still), 255 for 31 7/8 steps or more.
    m_gapLattice.resize(d.size());
    tbb::parallel_for(size_t(0), d.size(), [&](size_t i) {
        m_gapLattice[i] = static_cast<uint8_t>(std::min(255.0f, std::floor(std::sqrt(d[i]) * 8)));
    });
    for (int a = 0; a < 3; ++a) m_gapCounts[a] = n[a];
    m_gapStep = s;
    m_gapUnit = static_cast<float>(s) * m_shape.voxelSize / 8;
}

}  // namespace sdft
