// A sparse block's (B+1)^3 vertices grouped by the neighbour entry that holds them in the compact
// layout (decision 10): code = (x == B) + 2 (y == B) + 4 (z == B), 0 for the block's own B^3.
#pragma once

#include <array>
#include <vector>

namespace sdft {

// Apron positions per block ((B+1)^3 - B^3: the vertices with some local coordinate equal to B)
// and the 64-bit mask words they take (.sdfg versions 3 and 4 store a mask per block).
inline int apronSize(int B) { return (B + 1) * (B + 1) * (B + 1) - B * B * B; }
inline int apronWords(int B) { return (apronSize(B) + 63) / 64; }
// The apron's local vertices, z slowest, x fastest: the order of the masks' bits and of the kept
// samples.
inline std::vector<std::array<int, 3>> apronPositions(int B) {
    std::vector<std::array<int, 3>> out;
    for (int k = 0; k <= B; ++k)
        for (int j = 0; j <= B; ++j)
            for (int i = 0; i <= B; ++i)
                if (i == B || j == B || k == B) out.push_back({i, j, k});
    return out;
}

struct ApronLayout {
    int B, V;
    struct Vertex {
        int expanded;       // index in the (B+1)^3 block, x fastest
        int ownerExpanded;  // the owner's local vertex (x, y, z mod B) in a (B+1)^3 block
        int ownerOwn;       // the same among the owner's B^3 own samples
        int x, y, z;        // local coordinates, 0..B
    };
    std::vector<Vertex> byCode[8];

    explicit ApronLayout(int blockSize) : B(blockSize), V(blockSize + 1) {
        for (int z = 0; z <= B; ++z)
            for (int y = 0; y <= B; ++y)
                for (int x = 0; x <= B; ++x) {
                    const int code = (x == B) | (y == B) << 1 | (z == B) << 2;
                    const int ox = x % B, oy = y % B, oz = z % B;
                    byCode[code].push_back({(z * V + y) * V + x, (oz * V + oy) * V + ox,
                                            (oz * B + oy) * B + ox, x, y, z});
                }
    }
};

// The block holding neighbour entry `code` of block b (b + the code's axis bits) into o; false
// when it lies past the grid's last block.
inline bool neighbourBlock(const int b[3], int code, const int blocks[3], int o[3]) {
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
        o[a] = b[a] + ((code >> a) & 1);
        inside = inside && o[a] < blocks[a];
    }
    return inside;
}

}  // namespace sdft
