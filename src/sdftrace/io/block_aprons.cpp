#include "block_aprons.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>

#include "sdftrace/core/error.h"
#include "sdftrace/exec/all_finite.h"
#include "sdftrace/field/block_apron_layout.h"

namespace sdft {

namespace {

struct Layout {
    int B, V, own, per, apron, words;
    int blocks[3];
    explicit Layout(const GridShape& s, int blockSize)
        : B(blockSize),
          V(blockSize + 1),
          own(B * B * B),
          per(V * V * V),
          apron(per - own),
          words((apron + 63) / 64) {
        for (int a = 0; a < 3; ++a) blocks[a] = (s.cells[a] + B - 1) / B;
    }
    // Index of p (mod B) in an owner's B^3 own samples.
    int ownIndex(const std::array<int, 3>& p) const {
        return ((p[2] % B) * B + p[1] % B) * B + p[0] % B;
    }
};

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace

ApronSamples splitAprons(const Grid& grid) {
    const Layout L(grid.shape(), grid.blockSize());
    const GridView view = grid.view();
    const std::vector<float>& samples = grid.blockSamples();  // B^3 own samples per block first
    const size_t surface = grid.surfaceBlockCount();
    // Per apron vertex (mask order): its neighbour entry and its index in that entry's samples,
    // which are the owner's own samples where the entry is shared, else a constant or private
    // block laid out the same way (decision 10).
    std::vector<std::pair<int, int>> vertex;
    for (const auto& p : apronPositions(L.B))
        vertex.push_back({(p[0] == L.B) | (p[1] == L.B) << 1 | (p[2] == L.B) << 2, L.ownIndex(p)});
    std::vector<std::array<int, 3>> blockOf(surface);  // per surface block, its coordinates
    grid.forEachPagedBlock([&](int bi, int bj, int bk, size_t slot) {
        const int32_t data = view.blockData[slot];
        if (data >= 0) blockOf[static_cast<size_t>(data)] = {bi, bj, bk};
    });
    // An apron vertex is implicit where its owner is a surface block holding the same value: all
    // of an entry that reads the owner's samples, else vertex by vertex.
    auto keptOf = [&](size_t s, auto&& keep) {
        const int32_t* nb = view.blockNeighbors + s * 8;
        int32_t own[8];  // per entry, the owner's own samples (a surface block), -1 for none
        for (int code = 1; code < 8; ++code) {
            int o[3];
            own[code] = neighbourBlock(blockOf[s].data(), code, L.blocks, o)
                            ? view.blockData[view.blockSlot(o[0], o[1], o[2])]
                            : -1;
        }
        for (int a = 0; a < L.apron; ++a) {
            const auto [code, index] = vertex[static_cast<size_t>(a)];
            if (own[code] >= 0 && nb[code] == own[code]) continue;
            const float v = samples[static_cast<size_t>(nb[code]) * L.own + index];
            if (own[code] < 0 ||
                !sameBits(v, samples[static_cast<size_t>(own[code]) * L.own + index]))
                keep(a, v);
        }
    };
    ApronSamples out;
    out.masks.assign(surface * L.words, 0);
    std::vector<uint32_t> kept(surface);
    // Pass 1: the masks; pass 2 (after the prefix sums) the kept samples.
    tbb::parallel_for(size_t(0), surface, [&](size_t s) {
        uint64_t* mask = out.masks.data() + s * L.words;
        keptOf(s, [&](int a, float) {
            mask[a / 64] |= uint64_t{1} << (a % 64);
            ++kept[s];
        });
    });
    std::vector<size_t> start(surface + 1, 0);
    for (size_t s = 0; s < surface; ++s) start[s + 1] = start[s] + kept[s];
    out.explicitly.resize(start[surface]);
    tbb::parallel_for(size_t(0), surface, [&](size_t s) {
        size_t n = start[s];
        keptOf(s, [&](int, float v) { out.explicitly[n++] = v; });
    });
    return out;
}

namespace {

InputError corruptAprons(const std::string& source, const std::string& what) {
    return InputError(source + ": corrupt compressed .sdfg: " + what);
}

// Per apron vertex (mask order): where it goes in a (B+1)^3 block, which neighbour owns it (bit 0:
// +x, 1: +y, 2: +z) and its index among that neighbour's own samples.
struct ApronEntry {
    int dst, neighbour, ownIndex;
};

// Surface block d (at bi, bj, bk) expanded to its (B+1)^3 samples in `block`: its own samples, its
// apron from its neighbours' own samples or, where `mask` says so, from `kept` (its kept samples in
// mask order). Returns the neighbour entries whose kept samples differ from their owner's (they
// stay private to the block).
uint8_t expandBlock(const SparseGridBuilder& builder, const Layout& L, const float* ownSamples,
                    const std::vector<ApronEntry>& entries, int bi, int bj, int bk, int32_t d,
                    const uint64_t* mask, const float* kept, float* block,
                    const std::string& source) {
    const float* own = ownSamples + static_cast<size_t>(d) * L.own;
    for (int k = 0; k < L.B; ++k)
        for (int j = 0; j < L.B; ++j)
            std::memcpy(block + (k * L.V + j) * L.V, own + (k * L.B + j) * L.B,
                        static_cast<size_t>(L.B) * sizeof(float));
    // The 7 neighbours' own samples (null: past the grid or without samples).
    const float* neighbour[8] = {nullptr};
    for (int code = 1; code < 8; ++code) {
        const int32_t n = builder.neighbourData(bi, bj, bk, code);
        if (n >= 0) neighbour[code] = ownSamples + static_cast<size_t>(n) * L.own;
    }
    uint8_t privateEntries = 0;
    for (int a = 0; a < L.apron; ++a) {
        const ApronEntry& e = entries[static_cast<size_t>(a)];
        const float* from = neighbour[e.neighbour];
        if ((mask[a / 64] >> (a % 64)) & 1u) {
            const float v = *kept++;
            if (from && !sameBits(v, from[e.ownIndex]))
                privateEntries |= static_cast<uint8_t>(1u << e.neighbour);
            block[e.dst] = v;
            continue;
        }
        if (!from) throw corruptAprons(source, "an apron sample refers to a block without samples");
        block[e.dst] = from[e.ownIndex];
    }
    if (!allFinite(block, static_cast<size_t>(L.per)))
        throw corruptAprons(source, "non-finite sample");
    return privateEntries;
}

}  // namespace

Grid joinAprons(SparseGridBuilder& builder, std::vector<uint64_t> masks, uint64_t keptCount,
                KeptApronReader read, uint64_t window, const std::string& source) {
    const GridView& shapeView = builder.view();
    const Layout L(shapeView.shape, shapeView.blockSize);
    const size_t surface = builder.surfaceBlocks();
    if (masks.size() != surface * L.words)
        throw corruptAprons(source, "the flags name " + std::to_string(surface) +
                                        " surface blocks; the apron masks do not");
    auto keptBy = [&](size_t d) {
        uint64_t kept = 0;
        for (int w = 0; w < L.words; ++w) kept += std::popcount(masks[d * L.words + w]);
        return kept;
    };
    std::vector<ApronEntry> entries;
    for (const auto& p : apronPositions(L.B))
        entries.push_back({(p[2] * L.V + p[1]) * L.V + p[0],
                           (p[0] == L.B) | (p[1] == L.B) << 1 | (p[2] == L.B) << 2, L.ownIndex(p)});
    const float* ownSamples = builder.ownSamples();
    // Windows of blocks [d0, d1) whose kept samples fit `window` (a block alone may exceed it),
    // each block's first kept sample counted from the window's.
    std::vector<uint32_t> first;
    window = std::min<uint64_t>(window, uint64_t{1} << 30);  // offsets within it fit 32 bits
    uint64_t base = 0;
    for (size_t d0 = 0, d1 = 0; d0 < surface; d0 = d1) {
        first.assign(1, 0);
        uint64_t run = 0;
        for (d1 = d0; d1 < surface; ++d1) {
            const uint64_t kept = keptBy(d1);
            if (d1 > d0 && run + kept > window) break;
            run += kept;
            first.push_back(static_cast<uint32_t>(run));
        }
        if (run > keptCount - base) throw corruptAprons(source, "explicit apron sample count");
        const float* kept = read(base, base + run);
        builder.forEachSurfaceBlock([&](int bi, int bj, int bk, int32_t d) {
            const size_t at = static_cast<size_t>(d);
            if (at < d0 || at >= d1) return;
            float block[9 * 9 * 9];  // (B+1)^3, B <= 8
            const uint8_t privateEntries =
                expandBlock(builder, L, ownSamples, entries, bi, bj, bk, d,
                            masks.data() + at * L.words, kept + first[at - d0], block, source);
            builder.addBlock(bi, bj, bk, block, privateEntries, /*ownInPlace=*/true);
        });
        base += run;
    }
    if (base != keptCount) throw corruptAprons(source, "explicit apron sample count");
    masks = {};  // and the reader's buffers, before the skip and Lipschitz tables are made
    read = nullptr;
    return builder.finish();
}

Grid joinAprons(SparseGridBuilder& builder, const ApronSamples& aprons, const std::string& source) {
    return joinAprons(
        builder, aprons.masks, aprons.explicitly.size(),
        [&](uint64_t from, uint64_t) { return aprons.explicitly.data() + from; },
        aprons.explicitly.size(), source);
}

}  // namespace sdft
