// Builds a sparse block grid (grid.h) block by block from each surface block's (B+1)^3 vertex
// samples (Jamriška §3), straight into the compact layout of decision 10: the block's B^3 own
// samples, its cell masks (§4.1) and Lipschitz bound, and its neighbour entries. No buffer of
// (B+1)^3 samples per block is ever held, so the importers and bakers that feed it peak at the
// grid's own size.
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <array>
#include <cstdint>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "sdftrace/field/block_table.h"
#include "sdftrace/field/grid.h"

namespace sdft {

// A sparse grid's sample blocks and derived tables as a file stores them (.sdfg version 5), so
// that loading need not recompute them (Grid's members of the same names).
struct StoredSparse {
    std::vector<float> blockSamples;                 // (surface + extra) * B^3
    std::vector<int32_t> blockNeighbors;             // surface * 8
    std::vector<int32_t> apronFrom;                  // extra
    std::vector<uint8_t> apronCode;                  // extra
    std::vector<uint64_t> cellMasks;                 // surface * ceil(B^3 / 64)
    std::vector<uint8_t> blockSkip, blockLipschitz;  // per slot
    std::vector<uint8_t> tileSkip, tileLipschitz;    // per tile
    float lipschitz = 1, gentleLipschitz = 1;
};

class SparseGridBuilder {
  public:
    // Validates the table (throws InputError naming `source`) and numbers its surface blocks in
    // flat block order (z, y, x). With `allocate` false the sample buffers are not made (a grid
    // from stored parts, fromStored).
    SparseGridBuilder(const GridShape& shape, int blockSize, float background, BlockTable table,
                      const std::string& source, bool allocate = true);

    // The grid from its stored blocks and tables, every index and code checked against the table
    // (throws InputError naming `source`); the builder must have been made with allocate false.
    Grid fromStored(StoredSparse parts, const std::string& source);

    size_t surfaceBlocks() const { return m_grid.m_surfaceBlocks; }
    // The grid's shape and tables (its sample buffers are not the final ones until finish).
    const GridView& view() const { return m_view; }
    // The surface blocks' B^3 own samples (x fastest, blocks in index order), zeros until they
    // are added: a loader may fill them in place and add each block with `ownInPlace`, so the
    // grid's samples are never copied.
    float* ownSamples() { return m_grid.m_blockSamples.data(); }
    // Per slot (GridView::blockSlot) the surface block's index, -1 for none.
    const std::vector<int32_t>& blockData() const { return m_grid.m_blockData; }
    // Tiles whose page is their own, in page order (BlockTable::ownTiles).
    const std::vector<int>& ownTiles() const { return m_grid.m_ownTiles; }
    // The surface-block index of block (bi, bj, bk)'s neighbour for entry `code` (the code's
    // axis bits added), -1 when it has no samples or lies past the grid.
    int32_t neighbourData(int bi, int bj, int bk, int code) const;
    // Calls f(bi, bj, bk, index) for every surface block, tiles in parallel.
    template <class F>
    void forEachSurfaceBlock(F&& f) const {
        m_grid.forEachPagedBlock([&](int bi, int bj, int bk, size_t slot) {
            const int32_t data = m_grid.m_blockData[slot];
            if (data >= 0) f(bi, bj, bk, data);
        });
    }

    // Adds surface block (bi, bj, bk) from its (B+1)^3 vertex samples, x fastest; safe to call
    // concurrently for distinct blocks. A vertex that two surface blocks share must have the same
    // value in both, bit for bit, except in the neighbour entries set in `privateEntries` (bit c:
    // entry c), which keep this block's samples of them in a private sample block. With
    // `ownInPlace` the block's own samples are already in ownSamples() and are not written (other
    // threads may be reading them as neighbours).
    void addBlock(int bi, int bj, int bk, const float* samples, uint8_t privateEntries = 0,
                  bool ownInPlace = false);

    // The grid, once every surface block has been added: the shared constant and private blocks
    // appended and numbered in block order (the same grid for the same input), the Lipschitz
    // bound and the empty-space skip tables.
    Grid finish();

  private:
    struct Private {
        int32_t data;
        int code;
        std::vector<float> own;  // B^3, the entry's vertices at their owner-local places
    };
    Grid m_grid;
    GridView m_view;             // of m_grid's tables (its buffers are not moved until finish)
    std::vector<float> m_worst;  // per surface block: its cells' largest squared gradient bound
                                 // (times h^2)
    tbb::enumerable_thread_specific<std::vector<Private>> m_privates;
    // The values that whole entries share (a neighbour entry of a constant takes code
    // kFirstConstant - id until finish() gives each value its shared block): few, mostly the
    // background's two signs, each looked up in a small per-thread cache before the shared map.
    int32_t constantId(uint32_t bits);
    std::mutex m_constantMutex;
    std::unordered_map<uint32_t, int32_t> m_constantIds;
    std::vector<uint32_t> m_constantBits;  // per id
    tbb::enumerable_thread_specific<std::vector<std::pair<uint32_t, int32_t>>> m_constantCache;
};

}  // namespace sdft
