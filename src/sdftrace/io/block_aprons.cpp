#include "block_aprons.h"

#include <tbb/parallel_for.h>

#include <array>
#include <bit>
#include <cstring>

#include "sdftrace/core/error.h"
#include "sdftrace/field/block_apron_layout.h"

namespace sdft {

namespace {

// The apron's local vertices (some coordinate == B), z slowest, x fastest.
std::vector<std::array<int, 3>> apronPositions(int B) {
    std::vector<std::array<int, 3>> out;
    for (int k = 0; k <= B; ++k)
        for (int j = 0; j <= B; ++j)
            for (int i = 0; i <= B; ++i)
                if (i == B || j == B || k == B) out.push_back({i, j, k});
    return out;
}

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
    void coords(size_t b, int c[3]) const {
        c[0] = static_cast<int>(b % blocks[0]);
        c[1] = static_cast<int>(b / blocks[0] % blocks[1]);
        c[2] = static_cast<int>(b / (static_cast<size_t>(blocks[0]) * blocks[1]));
    }
    // The block owning apron vertex p of block c (p's coordinates == B step to the neighbour);
    // false when it lies past the grid's last block.
    bool owner(const int c[3], const std::array<int, 3>& p, size_t& block) const {
        int o[3];
        for (int a = 0; a < 3; ++a) {
            o[a] = c[a] + (p[a] == B);
            if (o[a] >= blocks[a]) return false;
        }
        block = (static_cast<size_t>(o[2]) * blocks[1] + o[1]) * blocks[0] + o[0];
        return true;
    }
    // Index of p (mod B) in an owner's B^3 own samples.
    int ownIndex(const std::array<int, 3>& p) const {
        return ((p[2] % B) * B + p[1] % B) * B + p[0] % B;
    }
};

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Per surface block (numbered by `surfaceOf`, per slot), its block coordinates.
std::vector<std::array<int, 3>> surfaceBlockCoords(const BlockTable& table,
                                                   const std::vector<int32_t>& surfaceOf,
                                                   size_t surface) {
    std::vector<std::array<int, 3>> blockOf(surface);
    const std::vector<int> own = table.ownTiles();
    tbb::parallel_for(size_t(0), own.size() / 3, [&](size_t p) {
        const size_t page = (p + kFirstOwnPage) * kPageEntries;
        forEachBlockOfTile(table.blocks, own[3 * p], own[3 * p + 1], own[3 * p + 2],
                           [&](int bi, int bj, int bk) {
                               const int32_t n = surfaceOf[page + pageLocal(bi, bj, bk)];
                               if (n >= 0) blockOf[static_cast<size_t>(n)] = {bi, bj, bk};
                           });
    });
    return blockOf;
}

}  // namespace

int apronSize(int B) { return (B + 1) * (B + 1) * (B + 1) - B * B * B; }
int apronWords(int B) { return (apronSize(B) + 63) / 64; }

SplitBlocks splitBlocks(const Grid& grid) {
    const Layout L(grid.shape(), grid.blockSize());
    const auto aprons = apronPositions(L.B);
    const GridView view = grid.view();
    const std::vector<float>& samples = grid.blockSamples();  // B^3 own samples per block first
    const size_t surface = grid.surfaceBlockCount();
    std::vector<size_t> blockOf(surface);  // surface index -> flat block index
    grid.forEachPagedBlock([&](int bi, int bj, int bk, size_t slot) {
        const int32_t data = view.blockData[slot];
        if (data >= 0)
            blockOf[static_cast<size_t>(data)] =
                (static_cast<size_t>(bk) * L.blocks[1] + bj) * L.blocks[0] + bi;
    });
    // The sample index of flat block o, -1 for none.
    auto dataOf = [&](size_t o) {
        int c[3];
        L.coords(o, c);
        return view.blockData[view.blockSlot(c[0], c[1], c[2])];
    };
    // Apron vertex p of surface block s, as its cells read it (through the neighbour entries).
    auto apronSample = [&](size_t s, const std::array<int, 3>& p) {
        return samples[view.blockSampleIndex(static_cast<int32_t>(s), p[0], p[1], p[2])];
    };
    SplitBlocks out;
    out.own.resize(surface * L.own);
    out.masks.assign(surface * L.words, 0);
    std::vector<uint32_t> kept(surface);
    // Pass 1: own samples and masks; pass 2 (after the prefix sums) the explicit samples.
    std::copy(samples.begin(), samples.begin() + static_cast<ptrdiff_t>(surface * L.own),
              out.own.begin());
    tbb::parallel_for(size_t(0), surface, [&](size_t s) {
        int c[3];
        L.coords(blockOf[s], c);
        uint64_t* mask = out.masks.data() + s * L.words;
        for (int a = 0; a < L.apron; ++a) {
            const auto& p = aprons[static_cast<size_t>(a)];
            const float v = apronSample(s, p);
            size_t o = 0;
            int32_t owner = -1;
            const bool implicit = L.owner(c, p, o) && (owner = dataOf(o)) >= 0 &&
                                  sameBits(v, samples[static_cast<size_t>(owner) * L.own +
                                                      static_cast<size_t>(L.ownIndex(p))]);
            if (!implicit) {
                mask[a / 64] |= uint64_t{1} << (a % 64);
                ++kept[s];
            }
        }
    });
    std::vector<size_t> start(surface + 1, 0);
    for (size_t s = 0; s < surface; ++s) start[s + 1] = start[s] + kept[s];
    out.explicitly.resize(start[surface]);
    tbb::parallel_for(size_t(0), surface, [&](size_t s) {
        const uint64_t* mask = out.masks.data() + s * L.words;
        size_t n = start[s];
        for (int a = 0; a < L.apron; ++a)
            if ((mask[a / 64] >> (a % 64)) & 1u) {
                const auto& p = aprons[static_cast<size_t>(a)];
                out.explicitly[n++] = apronSample(s, p);
            }
    });
    return out;
}

std::vector<float> joinBlocks(const GridShape& shape, int blockSize, const BlockTable& table,
                              const SplitBlocks& split, const std::string& source) {
    const Layout L(shape, blockSize);
    const auto aprons = apronPositions(L.B);
    auto corrupt = [&](const std::string& what) {
        return InputError(source + ": corrupt compressed .sdfg: " + what);
    };
    for (int a = 0; a < 3; ++a)
        if (table.blocks[a] != L.blocks[a]) throw corrupt("block table size");
    // Per slot the surface index (flat block order), and per surface block its coordinates.
    size_t surface = 0;
    const std::vector<int32_t> surfaceOf = table.surfaceIndices(surface);
    if (surfaceOf.empty() && surface > 0) throw corrupt("more than 2^31 - 1 surface blocks");
    if (split.own.size() != surface * L.own || split.masks.size() != surface * L.words)
        throw corrupt("the flags name " + std::to_string(surface) +
                      " surface blocks; the samples and masks do not");
    const std::vector<std::array<int, 3>> blockOf = surfaceBlockCoords(table, surfaceOf, surface);
    std::vector<size_t> start(surface + 1, 0);
    for (size_t s = 0; s < surface; ++s) {
        size_t kept = 0;
        for (int w = 0; w < L.words; ++w) kept += std::popcount(split.masks[s * L.words + w]);
        start[s + 1] = start[s] + kept;
    }
    if (start[surface] != split.explicitly.size()) throw corrupt("explicit apron sample count");
    // Per apron vertex, once: where it goes, which neighbour owns it (bit 0: +x, 1: +y, 2: +z)
    // and its index among that neighbour's own samples.
    struct Entry {
        int dst, neighbour, ownIndex;
    };
    std::vector<Entry> entries;
    for (const auto& p : aprons)
        entries.push_back({(p[2] * L.V + p[1]) * L.V + p[0],
                           (p[0] == L.B) | (p[1] == L.B) << 1 | (p[2] == L.B) << 2, L.ownIndex(p)});
    std::vector<float> samples(surface * L.per);
    tbb::parallel_for(size_t(0), surface, [&](size_t s) {
        float* dst = samples.data() + s * L.per;
        const float* own = split.own.data() + s * L.own;
        for (int k = 0; k < L.B; ++k)
            for (int j = 0; j < L.B; ++j)
                for (int i = 0; i < L.B; ++i)
                    dst[(k * L.V + j) * L.V + i] = own[(k * L.B + j) * L.B + i];
        const int* c = blockOf[s].data();
        // The 7 neighbours' own samples (null: past the grid or without samples).
        const float* neighbour[8] = {nullptr};
        for (int code = 1; code < 8; ++code) {
            int o[3];
            if (!neighbourBlock(c, code, L.blocks, o)) continue;
            const int32_t n = surfaceOf[table.slot(o[0], o[1], o[2])];
            if (n >= 0) neighbour[code] = split.own.data() + static_cast<size_t>(n) * L.own;
        }
        const uint64_t* mask = split.masks.data() + s * L.words;
        size_t n = start[s];
        for (int a = 0; a < L.apron; ++a) {
            const Entry& e = entries[static_cast<size_t>(a)];
            if ((mask[a / 64] >> (a % 64)) & 1u) {
                dst[e.dst] = split.explicitly[n++];
                continue;
            }
            const float* from = neighbour[e.neighbour];
            if (!from) throw corrupt("an apron sample refers to a block without samples");
            dst[e.dst] = from[e.ownIndex];
        }
        for (int a = L.apron; a < L.words * 64; ++a)
            if ((mask[a / 64] >> (a % 64)) & 1u) throw corrupt("apron mask bits past the apron");
    });
    return samples;
}

}  // namespace sdft
