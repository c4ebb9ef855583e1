#include "sdftrace/field/sparse_grid_builder.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>

#include "block_apron_layout.h"
#include "sdftrace/core/error.h"
#include "sdftrace/core/macros.h"
#include "sdftrace/exec/all_finite.h"
#include "sdftrace/exec/huge_pages.h"
#include "sdftrace/field/block_masks.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace sdft {

// Jamriška §4.1's cell masks and the Lipschitz bound of each block (block_masks.h), the block of
// 4 in SSE2 where the CPU has it.
namespace {
#if defined(__SSE2__)
// blockMasksAndBoundOf<4> in SSE2 (the x86-64 baseline): a row of 4 cells is one vector. The same
// operations in the same order, so the same values.
float blockMasksAndBound4(const float* s, int ni, int nj, int nk, uint64_t* mask) {
    constexpr int V = 5, sy = V, sz = V * V;
    const __m128 sign = _mm_set1_ps(-0.0f);
    auto absDiff = [&](const float* a, const float* b) {
        return _mm_andnot_ps(sign, _mm_sub_ps(_mm_loadu_ps(a), _mm_loadu_ps(b)));
    };
    // Edge differences: x-edges 4 per row; y- and z-edges 5 per row (padded for loads at +1).
    alignas(16) float ex[V][V][4];
    float ey[V][4][8], ez[4][V][8];
    uint32_t negative[V][V];
    for (int k = 0; k < V; ++k)
        for (int j = 0; j < V; ++j) {
            const float* r = s + k * sz + j * sy;
            _mm_store_ps(ex[k][j], absDiff(r + 1, r));
            if (j < 4) {
                _mm_storeu_ps(ey[k][j], absDiff(r + sy, r));
                ey[k][j][4] = std::fabs(r[sy + 4] - r[4]);
            }
            if (k < 4) {
                _mm_storeu_ps(ez[k][j], absDiff(r + sz, r));
                ez[k][j][4] = std::fabs(r[sz + 4] - r[4]);
            }
            negative[k][j] = static_cast<uint32_t>(
                                 _mm_movemask_ps(_mm_cmplt_ps(_mm_loadu_ps(r), _mm_setzero_ps()))) |
                             static_cast<uint32_t>(r[4] < 0) << 4;
        }
    // Lanes of cells past ni (a block cut by the grid's face) count for nothing.
    const __m128 keep = _mm_castsi128_ps(
        _mm_set_epi32(ni > 3 ? -1 : 0, ni > 2 ? -1 : 0, ni > 1 ? -1 : 0, ni > 0 ? -1 : 0));
    __m128 worst = _mm_setzero_ps();
    for (int k = 0; k < nk; ++k)
        for (int j = 0; j < nj; ++j) {
            const __m128 gx =
                _mm_max_ps(_mm_max_ps(_mm_load_ps(ex[k][j]), _mm_load_ps(ex[k][j + 1])),
                           _mm_max_ps(_mm_load_ps(ex[k + 1][j]), _mm_load_ps(ex[k + 1][j + 1])));
            const __m128 gy =
                _mm_max_ps(_mm_max_ps(_mm_loadu_ps(ey[k][j]), _mm_loadu_ps(ey[k][j] + 1)),
                           _mm_max_ps(_mm_loadu_ps(ey[k + 1][j]), _mm_loadu_ps(ey[k + 1][j] + 1)));
            const __m128 gz =
                _mm_max_ps(_mm_max_ps(_mm_loadu_ps(ez[k][j]), _mm_loadu_ps(ez[k][j] + 1)),
                           _mm_max_ps(_mm_loadu_ps(ez[k][j + 1]), _mm_loadu_ps(ez[k][j + 1] + 1)));
            const __m128 bound =
                _mm_add_ps(_mm_add_ps(_mm_mul_ps(gx, gx), _mm_mul_ps(gy, gy)), _mm_mul_ps(gz, gz));
            worst = _mm_max_ps(worst, _mm_and_ps(bound, keep));
            const uint32_t change = rowSignChanges(negative[k][j], negative[k][j + 1],
                                                   negative[k + 1][j], negative[k + 1][j + 1], ni);
            const int bit = (k * 4 + j) * 4;
            mask[bit / 64] |= static_cast<uint64_t>(change) << (bit % 64);
        }
    alignas(16) float lanes[4];
    _mm_store_ps(lanes, worst);
    return std::max(std::max(lanes[0], lanes[1]), std::max(lanes[2], lanes[3]));
}
#else
float blockMasksAndBound4(const float* s, int ni, int nj, int nk, uint64_t* mask) {
    return blockMasksAndBoundOf<4>(s, ni, nj, nk, mask);
}
#endif

float blockMasksAndBound(const float* s, int B, int ni, int nj, int nk, uint64_t* mask) {
    return B == 8 ? blockMasksAndBoundOf<8>(s, ni, nj, nk, mask)
                  : blockMasksAndBound4(s, ni, nj, nk, mask);
}
}  // namespace

namespace {
bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }
uint32_t bitsOf(float a) {
    uint32_t u;
    std::memcpy(&u, &a, sizeof u);
    return u;
}
constexpr int32_t kPrivate = -3, kFirstConstant = -4;  // constant ids: kFirstConstant - id
// A block's B^3 own samples (local coordinates 0..B-1) out of its (B+1)^3, row by row.
template <int B>
void copyOwn(const float* expanded, float* own) {
    constexpr int V = B + 1;
    for (int z = 0; z < B; ++z)
        for (int y = 0; y < B; ++y)
            std::memcpy(own + (z * B + y) * B, expanded + (z * V + y) * V, B * sizeof(float));
}
}  // namespace

SparseGridBuilder::SparseGridBuilder(const GridShape& shape, int B, float background,
                                     BlockTable table, const std::string& source, bool allocate) {
    Grid& g = m_grid;
    g.m_kind = GridKind::Sparse;
    g.m_shape = shape;
    SDFT_CHECK(B == 4 || B == 8);  // GridView::blockShift
    g.m_blockSize = B;
    g.m_background = background;
    for (int a = 0; a < 3; ++a) {
        g.m_blocks[a] = (shape.cells[a] + B - 1) / B;
        SDFT_CHECK(table.blocks[a] == g.m_blocks[a]);
        g.m_tiles[a] = table.tiles[a];
    }
    // Own pages are numbered in tile order (the flat sample order below relies on it).
    int32_t nextPage = kFirstOwnPage;
    for (int32_t page : table.tilePage) {
        SDFT_CHECK(page >= kOutsidePage && page <= nextPage);
        if (page >= kFirstOwnPage) {
            SDFT_CHECK(page == nextPage);
            ++nextPage;
        }
    }
    SDFT_CHECK(table.flags.size() == static_cast<size_t>(nextPage) * kPageEntries);
    for (size_t slot = 0; slot < table.flags.size(); ++slot)
        if (table.flags[slot] > static_cast<uint8_t>(BlockFlag::Surface))
            throw InputError(source + ": a block has an invalid flag " +
                             std::to_string(table.flags[slot]) +
                             " (accepted: 0 outside, 1 inside, 2 surface)");
    size_t surface = 0;
    g.m_blockData = table.surfaceIndices(surface);
    if (surface > static_cast<size_t>(INT32_MAX))
        throw InputError(source + ": " + std::to_string(surface) +
                         " surface blocks (at most 2^31 - 1 are accepted)");
    g.m_ownTiles = table.ownTiles();
    g.m_tilePage = std::move(table.tilePage);
    g.m_flags = std::move(table.flags);
    g.m_surfaceBlocks = surface;
    const size_t own = static_cast<size_t>(B) * B * B;
    if (!allocate) return;
    // Room for the constant and private sample blocks finish() appends (a few per thousand
    // surface blocks), so that appending them moves nothing.
    const size_t room = (surface + surface / 64 + 16) * own;
    std::vector<float>().swap(g.m_blockSamples);
    g.m_blockSamples.reserve(room);
    adviseHugePages(g.m_blockSamples.data(), room * sizeof(float));
    touchPages(g.m_blockSamples.data(), surface * own * sizeof(float));
    g.m_blockSamples.assign(surface * own, 0.0f);
    assignHuge(g.m_cellMasks, surface * static_cast<size_t>((B * B * B + 63) / 64), uint64_t{0});
    assignHuge(g.m_blockNeighbors, surface * 8,
               int32_t{-1});  // entry 0 set when the block is added
    m_worst.assign(surface, 0.0f);
    m_view = g.view();
}

int32_t SparseGridBuilder::neighbourData(int bi, int bj, int bk, int code) const {
    const int b[3] = {bi, bj, bk};
    int o[3];
    return neighbourBlock(b, code, m_view.blocks, o)
               ? m_grid.m_blockData[m_view.blockSlot(o[0], o[1], o[2])]
               : -1;
}

// Decision 10: the block's own samples and masks, and per far neighbour entry the owner's
// samples (a surface block: the same values), else a shared constant where the block's
// vertices there are one value, else a private copy of them.
void SparseGridBuilder::addBlock(int bi, int bj, int bk, const float* samples,
                                 uint8_t privateEntries, bool ownInPlace) {
    Grid& g = m_grid;
    const int B = g.m_blockSize;
    const GridView& view = m_view;
    const int32_t data = g.m_blockData[view.blockSlot(bi, bj, bk)];
    SDFT_CHECK(data >= 0);
    const size_t own = static_cast<size_t>(B) * B * B;
    const int ni = std::min(B, g.m_shape.cells[0] - bi * B),
              nj = std::min(B, g.m_shape.cells[1] - bj * B),
              nk = std::min(B, g.m_shape.cells[2] - bk * B);
    uint64_t* mask = g.m_cellMasks.data() + static_cast<size_t>(data) * view.wordsPerMask();
    m_worst[static_cast<size_t>(data)] = blockMasksAndBound(samples, B, ni, nj, nk, mask);
    float* dst = g.m_blockSamples.data() + static_cast<size_t>(data) * own;
    if (!ownInPlace) {
        if (B == 4)
            copyOwn<4>(samples, dst);
        else
            copyOwn<8>(samples, dst);
    }
    static const ApronLayout layouts[2] = {ApronLayout(4), ApronLayout(8)};
    const ApronLayout& L = layouts[B == 8];
    int32_t* nb = g.m_blockNeighbors.data() + static_cast<size_t>(data) * 8;
    nb[0] = data;
    for (int code = 1; code < 8; ++code) {
        const auto& vs = L.byCode[code];
        if (!((privateEntries >> code) & 1)) {
            const int32_t od = neighbourData(bi, bj, bk, code);
            if (od >= 0) {
                nb[code] = od;
                continue;
            }
            const float first = samples[vs[0].expanded];
            bool uniform = true;
            for (const auto& v : vs) uniform = uniform && sameBits(samples[v.expanded], first);
            if (uniform) {
                nb[code] = kFirstConstant - constantId(bitsOf(first));
                continue;
            }
        }
        nb[code] = kPrivate;
        Private p{data, code, std::vector<float>(own, 0.0f)};
        for (const auto& v : vs) p.own[static_cast<size_t>(v.ownerOwn)] = samples[v.expanded];
        m_privates.local().push_back(std::move(p));
    }
}

Grid SparseGridBuilder::fromStored(StoredSparse p, const std::string& source) {
    Grid& g = m_grid;
    const size_t S = g.m_surfaceBlocks,
                 own = static_cast<size_t>(g.m_blockSize) * g.m_blockSize * g.m_blockSize;
    const size_t extra = p.apronFrom.size(), blocks = S + extra;
    auto corrupt = [&](const std::string& what) {
        return InputError(source + ": corrupt stored grid: " + what);
    };
    if (p.blockSamples.size() != blocks * own || p.blockNeighbors.size() != S * 8 ||
        p.apronCode.size() != extra || p.cellMasks.size() != S * ((own + 63) / 64) ||
        p.blockSkip.size() != g.m_flags.size() || p.blockLipschitz.size() != g.m_flags.size() ||
        p.tileSkip.size() != g.m_tilePage.size() || p.tileLipschitz.size() != g.m_tilePage.size())
        throw corrupt("a table's size does not fit the block table");
    if (blocks > static_cast<size_t>(INT32_MAX)) throw corrupt("more than 2^31 - 1 sample blocks");
    if (!(p.lipschitz >= 1) || !std::isfinite(p.lipschitz) || !(p.gentleLipschitz > 0) ||
        !(p.gentleLipschitz <= p.lipschitz))
        throw corrupt("Lipschitz bounds");
    // Indices and codes in range (every view lookup then stays in its arrays), finite samples.
    std::atomic<bool> ok{true};
    tbb::parallel_for(size_t(0), S, [&](size_t s) {
        const int32_t* nb = p.blockNeighbors.data() + 8 * s;
        bool good = nb[0] == static_cast<int32_t>(s);
        for (int c = 1; c < 8; ++c)
            good = good && nb[c] >= 0 && static_cast<size_t>(nb[c]) < blocks;
        if (!good) ok = false;
    });
    for (size_t e = 0; e < extra; ++e)
        if (p.apronFrom[e] < -1 || p.apronFrom[e] >= static_cast<int32_t>(S) || p.apronCode[e] > 7)
            ok = false;
    for (const auto* codes : {&p.blockLipschitz, &p.tileLipschitz})
        if (std::any_of(codes->begin(), codes->end(), [](uint8_t c) { return c > 1; })) ok = false;
    if (!ok) throw corrupt("a sample block, neighbour entry or Lipschitz code out of range");
    if (!allFinite(p.blockSamples.data(), p.blockSamples.size()))
        throw corrupt("non-finite sample");
    g.m_blockSamples = std::move(p.blockSamples);
    g.m_blockNeighbors = std::move(p.blockNeighbors);
    g.m_apronFrom = std::move(p.apronFrom);
    g.m_apronCode = std::move(p.apronCode);
    g.m_cellMasks = std::move(p.cellMasks);
    g.m_blockSkip = std::move(p.blockSkip);
    g.m_blockLipschitz = std::move(p.blockLipschitz);
    g.m_tileSkip = std::move(p.tileSkip);
    g.m_tileLipschitz = std::move(p.tileLipschitz);
    g.m_lipschitz = p.lipschitz;
    g.m_gentleLipschitz = p.gentleLipschitz;
    return std::move(g);
}

int32_t SparseGridBuilder::constantId(uint32_t bits) {
    auto& cache = m_constantCache.local();
    for (const auto& [b, id] : cache)
        if (b == bits) return id;
    int32_t id;
    {
        std::lock_guard<std::mutex> lock(m_constantMutex);
        const auto [it, added] =
            m_constantIds.try_emplace(bits, static_cast<int32_t>(m_constantBits.size()));
        if (added) {
            if (m_constantBits.size() == size_t{INT32_MAX} - 4)  // its code would not fit
                throw InputError("sparse grid: more than 2^31 - 5 distinct apron constants");
            m_constantBits.push_back(bits);
        }
        id = it->second;
    }
    if (cache.size() == 4) cache.erase(cache.begin());
    cache.push_back({bits, id});
    return id;
}

Grid SparseGridBuilder::finish() {
    Grid& g = m_grid;
    const int B = g.m_blockSize;
    const size_t own = static_cast<size_t>(B) * B * B, S = g.m_surfaceBlocks;
    std::vector<Private> privates;
    for (auto& list : m_privates)
        for (auto& p : list) privates.push_back(std::move(p));
    std::sort(privates.begin(), privates.end(), [](const Private& a, const Private& b) {
        return a.data != b.data ? a.data < b.data : a.code < b.code;
    });
    // The extra sample blocks, numbered in block and entry order.
    std::vector<int32_t> constantBlock(m_constantBits.size(), -1);  // per id, once numbered
    g.m_apronFrom.clear();
    g.m_apronCode.clear();
    size_t nextPrivate = 0;
    int32_t next = static_cast<int32_t>(S);
    for (size_t s = 0; s < S; ++s) {
        SDFT_CHECK(g.m_blockNeighbors[s * 8] == static_cast<int32_t>(s));  // every block added
        for (int code = 1; code < 8; ++code) {
            int32_t& nb = g.m_blockNeighbors[s * 8 + static_cast<size_t>(code)];
            if (nb >= 0) continue;
            if (nb <= kFirstConstant) {
                const size_t id = static_cast<size_t>(kFirstConstant - nb);
                if (constantBlock[id] >= 0) {
                    nb = constantBlock[id];
                    continue;
                }
                float value;
                std::memcpy(&value, &m_constantBits[id], sizeof value);
                constantBlock[id] = next;
                g.m_blockSamples.insert(g.m_blockSamples.end(), own, value);
                g.m_apronFrom.push_back(-1);
                g.m_apronCode.push_back(0);
            } else {
                SDFT_CHECK(nextPrivate < privates.size());
                const Private& p = privates[nextPrivate++];
                SDFT_CHECK(p.data == static_cast<int32_t>(s) && p.code == code);
                g.m_blockSamples.insert(g.m_blockSamples.end(), p.own.begin(), p.own.end());
                g.m_apronFrom.push_back(static_cast<int32_t>(s));
                g.m_apronCode.push_back(static_cast<uint8_t>(code));
            }
            if (next == INT32_MAX)
                throw InputError("sparse grid: more than 2^31 - 1 sample blocks");
            nb = next++;
        }
    }
    m_constantIds = {};
    m_constantBits = std::vector<uint32_t>();
    float worst = 0;
    for (float w : m_worst) worst = std::max(worst, w);
    // The outside extension sqrt(d^2 + f(q)^2) is 1-Lipschitz in d; never report below 1.
    g.m_lipschitz = std::max(1.0f, std::sqrt(worst) / g.m_shape.voxelSize);
    g.computeBlockSkip();
    g.computeLocalLipschitz(m_worst);
    m_worst = std::vector<float>();
    return std::move(g);
}

}  // namespace sdft
