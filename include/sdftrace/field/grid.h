// Sampled distance fields (Liktor 2008, §3; Jamriška 2010, §3): samples at the vertices of a
// regular grid, reconstructed by trilinear interpolation. Two layouts share one trivially copyable
// view:
//  - dense: every vertex stored;
//  - sparse block grid: a coarse grid of blocks of B^3 cells (B = 4 or 8), each flagged inside,
//    outside or surface; only surface blocks store samples, with a bit mask of the cells that
//    contain the surface (§4.1). Jamriška §3 keeps each block's (B+1)^3 vertices; here a block
//    stores the B^3 vertices it owns (local coordinates 0..B-1) and reads its cells' far vertices
//    (a local coordinate == B: its "apron") from the blocks that own them through a table of 8
//    sample-block indices per surface block (itself, +x, +y, +xy, +z, +xz, +yz, +xyz), as an
//    OpenVDB leaf holds 8^3 voxels and no more: 1.95x fewer samples at B = 4 (decision 10). A
//    neighbour without samples points to a shared constant sample block, one per value; where a
//    neighbour's samples differ from the apron a block was built with, it points to a private
//    copy, so every cell reads exactly the corners it was built with. The per-block tables are
//    paged by tiles of 8^3 blocks (block_table.h), so that they follow the surface, not the
//    bounding box.
// Buffers are flat (std::vector) and the view holds plain pointers, so a device upload is one copy
// per buffer (docs/design.md; NanoVDB's handle + flat layout).
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <type_traits>
#include <vector>

#include "sdftrace/field/block_table.h"
#include "sdftrace/math/ray.h"

namespace sdft {

enum class GridKind : uint8_t { Dense = 0, Sparse = 1 };
enum class BlockFlag : uint8_t { Outside = 0, Inside = 1, Surface = 2 };

// Geometry shared by both layouts: `cells` cells per axis, vertex (0,0,0) at `origin`, cubic
// voxels.
struct GridShape {
    int cells[3] = {0, 0, 0};
    Vec3 origin;
    float voxelSize = 1;

    SDFT_HOST_DEVICE int vertices(int axis) const { return cells[axis] + 1; }
    Bounds3 bounds() const {
        return {origin, origin + Vec3(cells[0], cells[1], cells[2]) * voxelSize};
    }
    size_t vertexCount() const {
        return static_cast<size_t>(cells[0] + 1) * (cells[1] + 1) * (cells[2] + 1);
    }
};

struct GridView {
    GridKind kind = GridKind::Dense;
    GridShape shape;
    float lipschitz = 1;  // of the trilinear reconstruction, computed from the samples
    // dense: vertexCount() samples, x fastest
    const float* samples = nullptr;
    // sparse
    int blockSize = 4;                  // B cells per block edge
    int blocks[3] = {0, 0, 0};          // coarse grid dimensions (in blocks)
    int tiles[3] = {0, 0, 0};           // tiles of 8^3 blocks (block_table.h)
    const int32_t* tilePage = nullptr;  // per tile: its page of per-block entries
    // Per block slot (blockSlot()):
    const uint8_t* flags = nullptr;      // BlockFlag
    const int32_t* blockData = nullptr;  // index of the block's B^3 own samples, -1 if none
    // Sample blocks of B^3 samples each, x fastest inside a block: the surface blocks' own (index
    // = blockData), then the shared constant and private apron blocks the neighbour table names.
    const float* blockSamples = nullptr;
    // Per surface block (by its blockData index), 8 sample-block indices: entry
    // (x == B) + 2 (y == B) + 4 (z == B) holds local vertex (x, y, z), x, y, z in 0..B, at
    // (x mod B, y mod B, z mod B); entry 0 is the block itself.
    const int32_t* blockNeighbors = nullptr;
    const uint64_t* cellMasks = nullptr;  // per surface block: B^3 bits, (B^3 + 63) / 64 words
    // Per block slot: its Chebyshev distance d (in blocks) to the nearest block with a
    // sign-changing cell (a set bit in its cell mask), 0 for those, exact up to 8 (larger
    // distances are stored as 9). A ray can hit the surface only in a block with d = 0 and may
    // skip the cube of side 2d - 1 around any other.
    const uint8_t* blockSkip = nullptr;
    // Per tile: the same distance in tiles (capped at 255) to the nearest tile holding a block
    // with d = 0; a ray in a tile with a nonzero entry may skip the cube of tiles of side 2d - 1.
    // Both are null for a traversal without empty-space skipping.
    const uint8_t* tileSkip = nullptr;
    // Local Lipschitz bounds of the reconstruction (Grid::computeLocalLipschitz), which
    // gridDistanceBound divides by instead of the global bound: a code per block slot of the own
    // pages (over the block and one block around it) and per tile for blocks of the shared
    // constant pages, 0 for `lipschitz` itself and 1 for the gentle blocks' lipschitzLevel[1].
    // Null: the global bound everywhere.
    const uint8_t* blockLipschitz = nullptr;
    const uint8_t* tileLipschitz = nullptr;
    float lipschitzLevel[2] = {1, 1};
    float background = 1;  // |value| assumed in non-surface blocks (a lower bound of the distance)
    // Optional (sparse narrow bands; Grid::computeGapLattice): at the vertices of a lattice of
    // step gapStep cells from the origin (gapCounts[a] per axis, x fastest), a lower bound of the
    // distance to the reconstruction's zero set in units of gapUnit (rounded down, 255: at least
    // that), which gridDistanceBound reads where the band's samples are clamped or absent.
    // Null: none.
    const uint8_t* gapLattice = nullptr;
    int gapCounts[3] = {0, 0, 0};
    int gapStep = 1;
    float gapUnit = 0;
    // Optional texture coordinates (Liktor 2008, §5.5.2): 3 floats per stored sample, beside the
    // distance (dense: per vertex; sparse: per surface-block sample), mapped to (u, v) by
    // `texcoordKind` (TexcoordKind).
    const float* texcoords = nullptr;
    int texcoordKind = 0;

    // log2 of blockSize (4 or 8): block coordinates by shifts, not divisions.
    SDFT_HOST_DEVICE int blockShift() const { return blockSize == 8 ? 3 : 2; }
    SDFT_HOST_DEVICE int wordsPerMask() const {
        return (blockSize * blockSize * blockSize + 63) / 64;
    }
    SDFT_HOST_DEVICE size_t tileIndex(int bi, int bj, int bk) const {
        return (static_cast<size_t>(bk >> kTileShift) * tiles[1] + (bj >> kTileShift)) * tiles[0] +
               (bi >> kTileShift);
    }
    // The slot of sparse block (bi, bj, bk) in the per-block tables.
    SDFT_HOST_DEVICE size_t blockSlot(int bi, int bj, int bk) const {
        return static_cast<size_t>(tilePage[tileIndex(bi, bj, bk)]) * kPageEntries +
               pageLocal(bi, bj, bk);
    }

    // Index into blockSamples of local vertex (x, y, z), each in 0..B, of surface block `data`.
    SDFT_HOST_DEVICE size_t blockSampleIndex(int32_t data, int x, int y, int z) const {
        const int sh = blockShift(), m = blockSize - 1;
        const int code = (x >> sh) | (y >> sh) << 1 | (z >> sh) << 2;
        const size_t from =
            static_cast<size_t>(blockNeighbors[static_cast<size_t>(data) * 8 + code]);
        return (from << (3 * sh)) + ((static_cast<size_t>(z & m) << sh | (y & m)) << sh | (x & m));
    }
    // Indices into blockSamples of the 8 corners of local cell (x, y, z), each in 0..B-1, of
    // surface block `data` (idx[di + 2 dj + 4 dk]; blockCornerIndicesOf).
    SDFT_HOST_DEVICE void blockCornerIndices(int32_t data, int x, int y, int z,
                                             size_t idx[8]) const;
    // The 8 corner samples of local cell (x, y, z) of surface block `data` (c[di + 2 dj + 4 dk]).
    SDFT_HOST_DEVICE void blockCellCorners(int32_t data, int x, int y, int z, float c[8]) const;
    // Sample at integer vertex (i, j, k), clamped to the grid.
    SDFT_HOST_DEVICE float vertex(int i, int j, int k) const;
    // The vertices that central differences at the 8 corners of cell (i, j, k) read, each
    // clamped to the grid as vertex() does: out[z][y][x] = vertex(i - 1 + x, j - 1 + y, k - 1 + z)
    // for the 32 entries with at most one of x, y, z in {0, 3} (the others are left unset), the
    // block lookups shared.
    SDFT_HOST_DEVICE void gradientStencil(int i, int j, int k, float out[4][4][4]) const;
    // gradientStencil for log2 of the block size SH (0: read at run time; dense grids).
    template <int SH>
    SDFT_HOST_DEVICE void gradientStencilOf(int i, int j, int k, float out[4][4][4]) const;
    // Whether a ray can meet the surface in the sparse block at slot `block`: with the skip
    // table, only in a block holding a sign-changing cell (the others' cells are never tested);
    // without it, in any surface block.
    SDFT_HOST_DEVICE bool mayHoldHit(size_t block) const {
        return blockSkip ? blockSkip[block] == 0
                         : flags[block] == static_cast<uint8_t>(BlockFlag::Surface);
    }
    // The 8 corner samples of cell (i, j, k), index = di + 2 dj + 4 dk.
    SDFT_HOST_DEVICE void cellCorners(int i, int j, int k, float c[8]) const;
    // +-background of a sparse block without samples, by its flag (cell (i, j, k) in it).
    SDFT_HOST_DEVICE float constantBlockValue(int i, int j, int k) const;
    // Trilinear reconstruction inside the grid; outside, a distance bound through the nearest grid
    // point q: sqrt(|p - q|^2 + max(f(q), 0)^2) (the surface lies in the box, which is convex).
    SDFT_HOST_DEVICE float sample(Vec3 p) const;
    // The cell (i, j, k) holding p, clamped to the grid, and p's position (u, v, w) in it.
    SDFT_HOST_DEVICE void locate(Vec3 p, int& i, int& j, int& k, float& u, float& v,
                                 float& w) const;
    // Trilinear interpolation at p, clamped to the grid (no outside extension).
    SDFT_HOST_DEVICE float interpolate(Vec3 p) const;
    // Indices of the 8 corner samples of cell (i, j, k) into `samples` (dense) or `blockSamples`
    // (sparse); false for a sparse block without samples.
    SDFT_HOST_DEVICE bool cornerIndices(int i, int j, int k, size_t idx[8]) const;
    // (u, v) at p from the interpolated texture-coordinate vectors; false without them.
    SDFT_HOST_DEVICE bool texcoordsAt(Vec3 p, float& u, float& v) const;
};

// How a grid's 3-vector texture coordinates map to (u, v): the vectors are the points where
// particles traced along the gradient left a helper surface, in the helper's frame (axis = z).
enum class TexcoordKind : int {
    None = 0,
    Sphere = 1,    // unit direction: u = longitude / 2 pi + 1/2, v = 1 - colatitude / pi
    Cylinder = 2,  // (cos, sin, height in [0, 1]): u = angle / 2 pi + 1/2, v = height
};

// Owner of the buffers a view points into.
class Grid {
  public:
    // A dense grid from samples (vertexCount() of them, x fastest).
    static Grid dense(const GridShape& shape, std::vector<float> samples);
    // Every vertex's value, x fastest (a sparse grid's dropped blocks give +-background): what
    // dense file formats store.
    std::vector<float> vertexSamples() const;
    // A sparse block grid from dense samples: blocks whose samples are all farther than `band`
    // voxels from the surface (and have no sign change) are flagged inside/outside and dropped.
    // Stored samples are clamped to +-band voxels (as in a narrow-band level set): still a
    // 1-Lipschitz lower bound of the distance, and exact in the band.
    static Grid sparseFromDense(const GridShape& shape, const std::vector<float>& samples,
                                int blockSize, float bandVoxels);

    // A complete block grid (complete_grid.cpp): every block keeps its samples, as RTSDF's
    // per-frame grids cover their volume (Tan et al. 2022, §2.5.1). It reconstructs what
    // sparseFromDense(shape, samples, blockSize, bandVoxels) does when every block lies within
    // the band, but its layout (block pages, sample blocks, neighbour entries: the apron entries
    // past the grid's far faces always private) depends on the shape alone, so that the next
    // frame's samples refresh it (refreshComplete) instead of sparsifying afresh.
    static Grid completeFromDense(const GridShape& shape, const std::vector<float>& samples,
                                  int blockSize, float bandVoxels);
    bool isComplete() const { return m_complete; }
    // This complete grid's layout with `samples` (vertexCount() of them, x fastest): the grid
    // completeFromDense(shape(), samples, ...) builds, array for array, its blocks refreshed in
    // parallel by refreshCompleteBlock (complete_block.h, the GPU's kernel body too).
    Grid refreshComplete(const std::vector<float>& samples) const;
    // The band (world units) a complete grid clamps its samples to.
    float completeBand() const { return m_completeBand; }

    GridView view() const;
    GridKind kind() const { return m_kind; }
    const GridShape& shape() const { return m_shape; }
    size_t memoryBytes() const;
    int blockSize() const { return m_blockSize; }
    // Number of blocks flagged inside, outside, surface (sparse only).
    void blockCounts(size_t& inside, size_t& outside, size_t& surface) const;
    // About what memoryBytes() will be for a sparse grid of `surface` surface blocks on table `t`
    // (a file's, before its samples are read): every term but the few shared apron blocks.
    static size_t sparseMemoryEstimate(const BlockTable& t, size_t surface, int blockSize);
    float background() const { return m_background; }
    // Bounds of the cells whose corner samples change sign (where the surface is); empty if none.
    Bounds3 surfaceBounds() const;
    float lipschitz() const { return m_lipschitz; }

    // Raw buffers, for file I/O and tests.
    const std::vector<float>& samples() const { return m_samples; }
    // Per block slot (GridView::blockSlot; pages 0 and 1 constant), and per tile.
    const std::vector<uint8_t>& flags() const { return m_flags; }
    const std::vector<int32_t>& blockData() const { return m_blockData; }
    const std::vector<int32_t>& tilePage() const { return m_tilePage; }
    const std::vector<uint8_t>& tileSkip() const { return m_tileSkip; }
    const std::vector<uint8_t>& tileLipschitz() const { return m_tileLipschitz; }
    const std::vector<uint8_t>& blockLipschitz() const { return m_blockLipschitz; }
    // Sample blocks (GridView::blockSamples): the surface blocks' B^3 own samples first.
    const std::vector<float>& blockSamples() const { return m_blockSamples; }
    // Per surface block, 8 sample-block indices (GridView::blockNeighbors).
    const std::vector<int32_t>& blockNeighbors() const { return m_blockNeighbors; }
    size_t surfaceBlockCount() const { return m_surfaceBlocks; }
    // The surface blocks' (B+1)^3 vertex samples each (x fastest, blocks in blockData order), as
    // Jamriška §3 stores them: what .sdfg files hold. The texture coordinates likewise (3 floats
    // per vertex), empty when the grid has none.
    std::vector<float> expandedBlockSamples() const;  // empty for dense grids
    std::vector<float> expandedTexcoords() const;
    // Writes surface block `data`'s (B+1)^3 samples (x fastest) into out.
    void expandBlock(int32_t data, float* out) const;
    const std::vector<uint64_t>& cellMasks() const { return m_cellMasks; }
    // Per sample block past the surface blocks: the surface block and neighbour entry it serves,
    // or -1 (a shared constant block); the entry's code.
    const std::vector<int32_t>& apronFrom() const { return m_apronFrom; }
    const std::vector<uint8_t>& apronCode() const { return m_apronCode; }
    // The second, gentler Lipschitz bound of the blocks coded 1 (GridView::lipschitzLevel[1]).
    float gentleLipschitz() const { return m_gentleLipschitz; }
    const std::vector<uint8_t>& blockSkip() const { return m_blockSkip; }
    // The gap lattice (GridView::gapLattice; gap_lattice.cpp): for a sparse narrow band, at the
    // vertices of a lattice of step s cells, a lower bound of the distance to the nearest cell
    // whose corners change sign, from an exact Euclidean distance transform of those cells at
    // step s, one byte each (eighths of a step, up to 31 7/8 steps). Beyond the band it stands in
    // for the clamp, so that what the grid reads there depends on the surface, not on the band's
    // width. s is the smallest step that keeps the lattice within maxVertices (0: a quarter of
    // the grid's own memory, at least 33^3 and at most 129^3 vertices). A no-op for dense and
    // complete grids (their samples are not clamped to a band) and for grids without a sign
    // change.
    void computeGapLattice(size_t maxVertices = 0);
    const std::vector<uint8_t>& gapLattice() const { return m_gapLattice; }
    int gapStep() const { return m_gapStep; }
    // World units per count of the lattice's bytes.
    float gapUnit() const { return m_gapUnit; }
    // Texture coordinates beside the distances (GridView::texcoords); empty when none.
    const std::vector<float>& texcoords() const { return m_texcoords; }
    TexcoordKind texcoordKind() const { return m_texcoordKind; }
    // Number of stored samples (dense: vertices; sparse: every sample block's).
    size_t storedSamples() const {
        return m_kind == GridKind::Dense ? m_samples.size() : m_blockSamples.size();
    }
    // Attaches 3 floats per stored sample; throws InputError naming `source` on a size mismatch or
    // non-finite values.
    void setTexcoords(TexcoordKind kind, std::vector<float> texcoords, const std::string& source);
    // The same from 3 floats per (B+1)^3 vertex of each surface block (expandedTexcoords(), as
    // files store them; sparse only): each stored sample takes its owner's vector.
    void setExpandedTexcoords(TexcoordKind kind, const std::vector<float>& texcoords,
                              const std::string& source);
    // Calls f(sample, block, x, y, z) for each stored sample that some cell reads as a vertex:
    // the surface block (blockData index) and its local vertex (x, y, z in 0..B) it stands for
    // (own samples, and private apron blocks' apron vertices; shared constant blocks stand for no
    // vertex of their own and are skipped). Sparse only; in parallel; the positions the
    // texture-coordinate bake traces from.
    void forEachStoredSample(
        const std::function<void(size_t sample, int32_t block, int x, int y, int z)>& f) const;

    // Rebuilds a sparse grid from its stored buffers (file loading): flat per-block flags (x
    // fastest) and the surface blocks' samples in that order; recomputes the cell masks and the
    // Lipschitz bound. Throws InputError naming `source` if the buffers are inconsistent.
    static Grid sparseFromBuffers(const GridShape& shape, int blockSize, float background,
                                  const std::vector<uint8_t>& flags,
                                  std::vector<float> blockSamples, const std::string& source);
    // The same from a two-level table (block_table.h): never a per-block array of the whole
    // bounding box. The samples are the surface blocks' in flat block order (z, y, x).
    static Grid sparseFromTable(const GridShape& shape, int blockSize, float background,
                                BlockTable table, std::vector<float> blockSamples,
                                const std::string& source);
    // The flat per-block flags (x fastest; sparse only): what .sdfg files store.
    std::vector<uint8_t> denseFlags() const;
    // Calls f(bi, bj, bk, slot) for each block inside the grid on a page of its own (the blocks
    // whose flags vary; the others are constant), tiles in parallel when `parallel`.
    void forEachPagedBlock(const std::function<void(int, int, int, size_t)>& f,
                           bool parallel = true) const;

  private:
    friend class SparseGridBuilder;  // fills the sparse layout (sparse_grid_builder.h)
    void computeLipschitz();         // dense
    void computeBlockSkip();         // sparse, from the flags and cell masks
    // Complete grids: the global bound, the skip tables and the local bounds from each block's
    // squared cell gradient bound (times h^2).
    void finishComplete(const std::vector<float>& blockWorst);
    // Sparse: m_blockLipschitz and m_tileLipschitz from each surface block's squared cell
    // gradient bound (times h^2).
    void computeLocalLipschitz(const std::vector<float>& blockWorst);

    GridKind m_kind = GridKind::Dense;
    GridShape m_shape;
    float m_lipschitz = 1;
    std::vector<float> m_samples;
    int m_blockSize = 4;
    int m_blocks[3] = {0, 0, 0};
    int m_tiles[3] = {0, 0, 0};
    float m_background = 1;
    std::vector<int32_t> m_tilePage;
    std::vector<uint8_t> m_tileSkip;
    std::vector<uint8_t> m_tileLipschitz, m_blockLipschitz;  // GridView::lipschitzLevel codes
    float m_gentleLipschitz = 1;
    std::vector<int> m_ownTiles;  // (ti, tj, tk) per own page, from kFirstOwnPage
    std::vector<uint8_t> m_flags;
    std::vector<int32_t> m_blockData;
    std::vector<float> m_blockSamples;
    std::vector<int32_t> m_blockNeighbors;
    size_t m_surfaceBlocks = 0;
    // Per sample block past the surface blocks: the surface block and neighbour entry it serves
    // (a private apron block), or -1 (a shared constant block).
    std::vector<int32_t> m_apronFrom;
    std::vector<uint8_t> m_apronCode;
    std::vector<uint64_t> m_cellMasks;
    std::vector<uint8_t> m_blockSkip;
    std::vector<float> m_texcoords;
    std::vector<uint8_t> m_gapLattice;
    int m_gapCounts[3] = {0, 0, 0};
    int m_gapStep = 1;
    float m_gapUnit = 0;
    TexcoordKind m_texcoordKind = TexcoordKind::None;
    bool m_complete = false;  // completeFromDense's layout
    float m_completeBand = 0;
};

// ---- inline view functions (GPU-ready) ----

// Whether a cell's 8 corner samples differ in sign: the cell contains the surface (§4.1).
SDFT_HOST_DEVICE inline bool cornersChangeSign(const float c[8]) {
    bool neg = false, pos = false;
    for (int i = 0; i < 8; ++i) (c[i] < 0 ? neg : pos) = true;
    return neg && pos;
}

SDFT_HOST_DEVICE inline int clampi(int v, int lo, int hi) {
    return v < lo ? lo : (v > hi ? hi : v);
}

// GridView::blockCornerIndices for a block size known at compile time: per axis the corner's
// offset inside its block and, for the cells below the block's far faces, the neighbour entry
// that holds it. No branches: most cells of a B = 4 block touch a far face.
template <int B>
SDFT_HOST_DEVICE inline void blockCornerIndicesOf(const int32_t* blockNeighbors, int32_t data,
                                                  int x, int y, int z, size_t idx[8]) {
    constexpr int m = B - 1;
    constexpr size_t own = B * B * B;
    const int32_t* nb = blockNeighbors + static_cast<size_t>(data) * 8;
    const int cx = x == m, cy = (y == m) << 1, cz = (z == m) << 2;
    const int x1 = (x + 1) & m, y0 = y * B, y1 = ((y + 1) & m) * B, z0 = z * B * B,
              z1 = ((z + 1) & m) * B * B;
    auto at = [&](int code) { return static_cast<size_t>(nb[code]) * own; };
    idx[0] = static_cast<size_t>(data) * own + z0 + y0 + x;
    idx[1] = at(cx) + z0 + y0 + x1;
    idx[2] = at(cy) + z0 + y1 + x;
    idx[3] = at(cx | cy) + z0 + y1 + x1;
    idx[4] = at(cz) + z1 + y0 + x;
    idx[5] = at(cx | cz) + z1 + y0 + x1;
    idx[6] = at(cy | cz) + z1 + y1 + x;
    idx[7] = at(cx | cy | cz) + z1 + y1 + x1;
}

// GridView::blockCellCorners for a block size known at compile time: the cells off the block's
// far faces (27 of 64 at B = 4) read 8 own samples with constant strides; the others go through
// the neighbour entries.
template <int B>
SDFT_HOST_DEVICE inline void blockCellCornersOf(const float* blockSamples,
                                                const int32_t* blockNeighbors, int32_t data, int x,
                                                int y, int z, float c[8]) {
    if (((x + 1) | (y + 1) | (z + 1)) < B) {
        const float* q =
            blockSamples + static_cast<size_t>(data) * (B * B * B) + (z * B + y) * B + x;
        c[0] = q[0], c[1] = q[1], c[2] = q[B], c[3] = q[B + 1];
        c[4] = q[B * B], c[5] = q[B * B + 1], c[6] = q[B * B + B], c[7] = q[B * B + B + 1];
        return;
    }
    size_t idx[8];
    blockCornerIndicesOf<B>(blockNeighbors, data, x, y, z, idx);
    for (int n = 0; n < 8; ++n) c[n] = blockSamples[idx[n]];
}

SDFT_HOST_DEVICE inline void GridView::blockCornerIndices(int32_t data, int x, int y, int z,
                                                          size_t idx[8]) const {
    if (blockSize == 8)
        blockCornerIndicesOf<8>(blockNeighbors, data, x, y, z, idx);
    else
        blockCornerIndicesOf<4>(blockNeighbors, data, x, y, z, idx);
}

SDFT_HOST_DEVICE inline void GridView::blockCellCorners(int32_t data, int x, int y, int z,
                                                        float c[8]) const {
    if (blockSize == 8)
        blockCellCornersOf<8>(blockSamples, blockNeighbors, data, x, y, z, c);
    else
        blockCellCornersOf<4>(blockSamples, blockNeighbors, data, x, y, z, c);
}

SDFT_HOST_DEVICE inline float GridView::vertex(int i, int j, int k) const {
    int nx = shape.cells[0], ny = shape.cells[1], nz = shape.cells[2];
    i = clampi(i, 0, nx);
    j = clampi(j, 0, ny);
    k = clampi(k, 0, nz);
    // A corner of the cell below the vertex (the last vertex of an axis belongs to the last cell):
    // its one sample read, not the cell's eight.
    const int ci = i < nx ? i : nx - 1, cj = j < ny ? j : ny - 1, ck = k < nz ? k : nz - 1;
    size_t idx[8];
    if (!cornerIndices(ci, cj, ck, idx)) return constantBlockValue(ci, cj, ck);
    const float* s = kind == GridKind::Dense ? samples : blockSamples;
    return s[idx[(i - ci) + 2 * (j - cj) + 4 * (k - ck)]];
}

// gradientStencil's neighbour entries: a vertex is read through the block of the cell below it,
// which is its own block (local coordinate v mod B) except for the last vertex of an axis whose
// cell count is a multiple of B. There, and only there, it lies in the block's apron (local B):
// code[a][d] gets axis a's entry bit. False when no vertex of the stencil starting at `start`
// is such a vertex.
SDFT_HOST_DEVICE inline bool stencilApronCodes(const int n[3], const int start[3], int B,
                                               int code[3][4]) {
    bool any = false;
    for (int a = 0; a < 3; ++a)
        if ((n[a] & (B - 1)) == 0 && start[a] + 3 >= n[a])
            for (int d = 0; d < 4; ++d)
                if (clampi(start[a] + d, 0, n[a]) == n[a]) {
                    code[a][d] = 1 << a;
                    any = true;
                }
    return any;
}

SDFT_HOST_DEVICE inline void GridView::gradientStencil(int i, int j, int k,
                                                       float out[4][4][4]) const {
    // The usual block sizes with their shifts as constants: the per-axis parts below cost a
    // third of the stencil with the shift read at run time.
    if (kind == GridKind::Sparse && blockSize == 4) return gradientStencilOf<2>(i, j, k, out);
    if (kind == GridKind::Sparse && blockSize == 8) return gradientStencilOf<3>(i, j, k, out);
    gradientStencilOf<0>(i, j, k, out);
}

template <int SH>
SDFT_HOST_DEVICE inline void GridView::gradientStencilOf(int i, int j, int k,
                                                         float out[4][4][4]) const {
    const int n[3] = {shape.cells[0], shape.cells[1], shape.cells[2]};
    const int start[3] = {i - 1, j - 1, k - 1};
    // Per axis and offset: the clamped vertex's part of the flat index (dense), or its tile's
    // coordinate, its block's part of the index in the tile's page and its part of the index
    // among that block's B^3 own samples (sparse; the block of the cell below the vertex, as in
    // vertex()).
    int tileOf[3][4];
    size_t localPart[3][4], samplePart[3][4];
    const int sh = SH > 0 ? SH : blockShift();
    const size_t vertexStride[3] = {1, static_cast<size_t>(n[0]) + 1,
                                    (static_cast<size_t>(n[0]) + 1) * (n[1] + 1)};
    for (int a = 0; a < 3; ++a)
        for (int d = 0; d < 4; ++d) {
            const int v = clampi(start[a] + d, 0, n[a]);
            if (kind == GridKind::Dense) {
                samplePart[a][d] = v * vertexStride[a];
                continue;
            }
            const int b = (v < n[a] ? v : n[a] - 1) >> sh;
            tileOf[a][d] = b >> kTileShift;
            localPart[a][d] = static_cast<size_t>(b & (kTileBlocks - 1)) << (kTileShift * a);
            samplePart[a][d] = static_cast<size_t>(v & ((1 << sh) - 1)) << (sh * a);
        }
    // The 32 entries: rows (y, z) both in {1, 2} with x = 0..3, rows with one of them in {0, 3}
    // with x = 1, 2.
    static constexpr int kEntries[32][3] = {
        {1, 0, 1}, {2, 0, 1}, {1, 0, 2}, {2, 0, 2}, {1, 3, 1}, {2, 3, 1}, {1, 3, 2}, {2, 3, 2},
        {1, 1, 0}, {2, 1, 0}, {1, 2, 0}, {2, 2, 0}, {1, 1, 3}, {2, 1, 3}, {1, 2, 3}, {2, 2, 3},
        {0, 1, 1}, {1, 1, 1}, {2, 1, 1}, {3, 1, 1}, {0, 2, 1}, {1, 2, 1}, {2, 2, 1}, {3, 2, 1},
        {0, 1, 2}, {1, 1, 2}, {2, 1, 2}, {3, 1, 2}, {0, 2, 2}, {1, 2, 2}, {2, 2, 2}, {3, 2, 2}};
    if (kind == GridKind::Dense) {
        for (const auto& e : kEntries)
            out[e[2]][e[1]][e[0]] =
                samples[samplePart[0][e[0]] + samplePart[1][e[1]] + samplePart[2][e[2]]];
        return;
    }
    int codePart[3][4] = {};
    const bool apron = stencilApronCodes(n, start, blockSize, codePart);
    // Most stencils lie in one tile (one page for all 32 entries); the others look up each
    // entry's tile. Own samples alone (the common case: the same loop as with (B+1)^3 blocks), or
    // through the neighbour entries at the grid's far faces.
    auto fill = [&](auto pageOf, auto withApron) {
#if defined(__GNUC__) && !defined(__clang__) && !defined(__CUDACC__)
#pragma GCC unroll 32
#endif
        for (const auto& e : kEntries) {
            const size_t b =
                pageOf(e) + localPart[0][e[0]] + localPart[1][e[1]] + localPart[2][e[2]];
            const int32_t data = blockData[b];
            size_t from = static_cast<size_t>(data);
            if constexpr (decltype(withApron)::value)
                if (data >= 0)
                    from = static_cast<size_t>(
                        blockNeighbors[static_cast<size_t>(data) * 8 + codePart[0][e[0]] +
                                       codePart[1][e[1]] + codePart[2][e[2]]]);
            out[e[2]][e[1]][e[0]] =
                data >= 0 ? blockSamples[(from << (3 * sh)) + samplePart[0][e[0]] +
                                         samplePart[1][e[1]] + samplePart[2][e[2]]]
                : flags[b] == static_cast<uint8_t>(BlockFlag::Inside) ? -background
                                                                      : background;
        }
    };
    auto pageAt = [&](int x, int y, int z) {
        return static_cast<size_t>(
                   tilePage[(static_cast<size_t>(tileOf[2][z]) * tiles[1] + tileOf[1][y]) *
                                tiles[0] +
                            tileOf[0][x]]) *
               kPageEntries;
    };
    auto anyPage = [&](const int(&e)[3]) { return pageAt(e[0], e[1], e[2]); };
    if (tileOf[0][0] == tileOf[0][3] && tileOf[1][0] == tileOf[1][3] &&
        tileOf[2][0] == tileOf[2][3] && !apron) {
        const size_t page = pageAt(0, 0, 0);
        fill([page](const int(&)[3]) { return page; }, std::false_type{});
    } else if (!apron) {
        fill(anyPage, std::false_type{});
    } else {
        fill(anyPage, std::true_type{});
    }
}

SDFT_HOST_DEVICE inline float GridView::constantBlockValue(int i, int j, int k) const {
    const int sh = blockShift();
    return flags[blockSlot(i >> sh, j >> sh, k >> sh)] == static_cast<uint8_t>(BlockFlag::Inside)
               ? -background
               : background;
}

SDFT_HOST_DEVICE inline void GridView::cellCorners(int i, int j, int k, float c[8]) const {
    // Jamriška §3: a surface block's cells read its own samples and its neighbours' (the apron);
    // other blocks are constant at +-background by their flag.
    if (kind == GridKind::Sparse) {
        const int sh = blockShift();
        const int bi = i >> sh, bj = j >> sh, bk = k >> sh;
        const int32_t data = blockData[blockSlot(bi, bj, bk)];
        if (data >= 0) {
            blockCellCorners(data, i - (bi << sh), j - (bj << sh), k - (bk << sh), c);
            return;
        }
    }
    size_t idx[8];
    if (!cornerIndices(i, j, k, idx)) {
        const float v = constantBlockValue(i, j, k);
        for (int n = 0; n < 8; ++n) c[n] = v;
        return;
    }
    const float* s = kind == GridKind::Dense ? samples : blockSamples;
    for (int n = 0; n < 8; ++n) c[n] = s[idx[n]];
}

SDFT_HOST_DEVICE inline void GridView::locate(Vec3 p, int& i, int& j, int& k, float& u, float& v,
                                              float& w) const {
    Vec3 g = (p - shape.origin) / shape.voxelSize;
    float fx = clampf(g.x, 0.0f, static_cast<float>(shape.cells[0]));
    float fy = clampf(g.y, 0.0f, static_cast<float>(shape.cells[1]));
    float fz = clampf(g.z, 0.0f, static_cast<float>(shape.cells[2]));
    i = clampi(static_cast<int>(fx), 0, shape.cells[0] - 1);
    j = clampi(static_cast<int>(fy), 0, shape.cells[1] - 1);
    k = clampi(static_cast<int>(fz), 0, shape.cells[2] - 1);
    u = fx - i, v = fy - j, w = fz - k;
}

// Trilinear interpolation of a cell's corners c[i + 2 j + 4 k] at local coordinates (u, v, w).
SDFT_HOST_DEVICE inline float trilinear(const float c[8], float u, float v, float w) {
    float c00 = c[0] + (c[1] - c[0]) * u, c10 = c[2] + (c[3] - c[2]) * u;
    float c01 = c[4] + (c[5] - c[4]) * u, c11 = c[6] + (c[7] - c[6]) * u;
    float c0 = c00 + (c10 - c00) * v, c1 = c01 + (c11 - c01) * v;
    return c0 + (c1 - c0) * w;
}

SDFT_HOST_DEVICE inline float GridView::interpolate(Vec3 p) const {
    int i, j, k;
    float u, v, w;
    locate(p, i, j, k, u, v, w);
    float c[8];
    cellCorners(i, j, k, c);
    return trilinear(c, u, v, w);
}

SDFT_HOST_DEVICE inline bool GridView::cornerIndices(int i, int j, int k, size_t idx[8]) const {
    size_t base, sy, sz;
    if (kind == GridKind::Dense) {
        sy = shape.cells[0] + 1;
        sz = sy * (shape.cells[1] + 1);
        base = k * sz + j * sy + i;
    } else {
        const int sh = blockShift();
        int bi = i >> sh, bj = j >> sh, bk = k >> sh;
        int32_t data = blockData[blockSlot(bi, bj, bk)];
        if (data < 0) return false;
        blockCornerIndices(data, i - (bi << sh), j - (bj << sh), k - (bk << sh), idx);
        return true;
    }
    idx[0] = base, idx[1] = base + 1, idx[2] = base + sy, idx[3] = base + sy + 1;
    idx[4] = base + sz, idx[5] = base + sz + 1, idx[6] = base + sz + sy;
    idx[7] = base + sz + sy + 1;
    return true;
}

SDFT_HOST_DEVICE inline bool GridView::texcoordsAt(Vec3 p, float& u, float& v) const {
    if (!texcoords || texcoordKind == 0) return false;
    int i, j, k;
    float a, b, c;
    locate(p, i, j, k, a, b, c);
    size_t idx[8];
    if (!cornerIndices(i, j, k, idx)) return false;
    Vec3 t(0.0f);
    for (int n = 0; n < 8; ++n) {
        float w = ((n & 1) ? a : 1 - a) * ((n & 2) ? b : 1 - b) * ((n & 4) ? c : 1 - c);
        const float* q = texcoords + 3 * idx[n];
        t += Vec3(q[0], q[1], q[2]) * w;
    }
    constexpr float kInvTwoPi = 0.159154943f, kInvPi = 0.318309886f;
    u = 0.5f + std::atan2(t.y, t.x) * kInvTwoPi;
    if (texcoordKind == static_cast<int>(TexcoordKind::Sphere)) {
        float len = length(t);
        if (!(len > 0)) return false;
        v = 1.0f - std::acos(clampf(t.z / len, -1.0f, 1.0f)) * kInvPi;
    } else {
        v = t.z;
    }
    return true;
}

SDFT_HOST_DEVICE inline float GridView::sample(Vec3 p) const {
    Bounds3 b{shape.origin, shape.origin + Vec3(static_cast<float>(shape.cells[0]),
                                                static_cast<float>(shape.cells[1]),
                                                static_cast<float>(shape.cells[2])) *
                                               shape.voxelSize};
    Vec3 q = min(max(p, b.lo), b.hi);
    float f = interpolate(q);
    Vec3 d = p - q;
    float out2 = dot(d, d);
    if (out2 == 0.0f) return f;
    float inside = maxf(f, 0.0f);
    return std::sqrt(out2 + inside * inside);
}

}  // namespace sdft
