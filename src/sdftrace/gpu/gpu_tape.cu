#include <algorithm>
#include <cstring>
#include <vector>

#include "cuda_check.h"
#include "sdftrace/gpu/gpu_device.h"
#include "sdftrace/gpu/gpu_tape.h"

namespace sdft {

namespace {

// The host arrays of a tape laid out in one buffer (256-byte aligned pieces), uploaded with one
// copy; each piece's device address is the buffer's plus its offset.
class Packer {
  public:
    // Reserves room for `bytes` bytes from `data`; returns the piece's offset.
    size_t add(const void* data, size_t bytes) {
        const size_t offset = (m_bytes.size() + 255) & ~size_t(255);
        m_bytes.resize(offset + bytes);
        if (bytes) std::memcpy(m_bytes.data() + offset, data, bytes);
        return offset;
    }
    template <class T>
    size_t add(const std::vector<T>& v) {
        return add(v.data(), v.size() * sizeof(T));
    }
    std::vector<unsigned char>& bytes() { return m_bytes; }

  private:
    std::vector<unsigned char> m_bytes;
};

// A host pointer of the view replaced by the device address of its piece; null where the view
// had none or the array is empty.
template <class T>
void relocate(const T*& field, const std::vector<T>& host, size_t offset,
              const unsigned char* base) {
    field = field && !host.empty() ? reinterpret_cast<const T*>(base + offset) : nullptr;
}

// f(view's pointer, grid's array) for every array a GridView points into, in one order.
template <class F>
void forEachGridArray(GridView& v, const Grid& g, F&& f) {
    f(v.samples, g.samples());
    f(v.tilePage, g.tilePage());
    f(v.tileSkip, g.tileSkip());
    f(v.flags, g.flags());
    f(v.blockData, g.blockData());
    f(v.blockSamples, g.blockSamples());
    f(v.blockNeighbors, g.blockNeighbors());
    f(v.cellMasks, g.cellMasks());
    f(v.blockSkip, g.blockSkip());
    f(v.texcoords, g.texcoords());
    f(v.tileLipschitz, g.tileLipschitz());
    f(v.blockLipschitz, g.blockLipschitz());
    f(v.gapLattice, g.gapLattice());
}

}  // namespace

struct GpuTape::Impl {
    void* buffer = nullptr;
    size_t bytes = 0;
    TapeView view;
    std::vector<const Grid*> grids;  // the tape's, in view order
    ~Impl() {
        if (buffer) cudaFree(buffer);
    }
};

GpuTape::GpuTape(const Tape& tape, const std::vector<GpuGridBinding>& bound)
    : m_impl(std::make_unique<Impl>()) {
    requireGpu("GPU tape");
    Packer pack;
    const std::span<const Instr> instrs = tape.instructions();
    const std::span<const float> consts = tape.constants();
    const size_t instrAt = pack.add(instrs.data(), instrs.size_bytes());
    const size_t constAt = pack.add(consts.data(), consts.size_bytes());
    // The pruned tapes and their cells (field/tape_prune.h), read through the same view.
    const PrunedTapes* pruned = tape.pruned();
    size_t prunedAt = 0, spansAt = 0, cellsAt = 0;
    if (pruned) {
        prunedAt = pack.add(pruned->instrs);
        spansAt = pack.add(pruned->spans);
        cellsAt = pack.add(pruned->cellTape);
    }
    // Each grid's arrays (their offsets in forEachGridArray's order), then their views; a bound
    // grid's view as given, nothing uploaded.
    std::vector<GridView> views;
    std::vector<size_t> offsets;
    std::vector<bool> onDevice;
    for (const auto& g : tape.grids()) {
        m_impl->grids.push_back(g.get());
        auto b = std::find_if(bound.begin(), bound.end(),
                              [&](const GpuGridBinding& x) { return x.grid == g.get(); });
        onDevice.push_back(b != bound.end());
        if (onDevice.back()) {
            views.push_back(b->view);
            continue;
        }
        views.push_back(g->view());
        forEachGridArray(views.back(), *g,
                         [&](auto&, const auto& host) { offsets.push_back(pack.add(host)); });
    }
    // The views' offsets are known now; their addresses once the buffer is allocated.
    const size_t viewsAt = pack.add(nullptr, 0);
    pack.bytes().resize(viewsAt + views.size() * sizeof(GridView));
    std::vector<unsigned char>& bytes = pack.bytes();
    SDFT_CUDA_CHECK(cudaMalloc(&m_impl->buffer, bytes.size() ? bytes.size() : 1));
    m_impl->bytes = bytes.size();
    const unsigned char* base = static_cast<const unsigned char*>(m_impl->buffer);
    size_t next = 0;
    for (size_t i = 0; i < views.size(); ++i) {
        if (!onDevice[i])
            forEachGridArray(views[i], *tape.grids()[i], [&](auto& field, const auto& host) {
                relocate(field, host, offsets[next++], base);
            });
        std::memcpy(bytes.data() + viewsAt + i * sizeof(GridView), &views[i], sizeof(GridView));
    }
    SDFT_CUDA_CHECK(cudaMemcpy(m_impl->buffer, bytes.data(), bytes.size(), cudaMemcpyHostToDevice));
    TapeView& v = m_impl->view;
    v = tape.view();
    v.instrs = reinterpret_cast<const Instr*>(base + instrAt);
    v.consts = reinterpret_cast<const float*>(base + constAt);
    if (pruned) {
        v.cells.instrs = reinterpret_cast<const Instr*>(base + prunedAt);
        v.cells.spans = reinterpret_cast<const uint32_t*>(base + spansAt);
        v.cells.cellTape = reinterpret_cast<const uint32_t*>(base + cellsAt);
    }
    v.grids = views.empty() ? nullptr : reinterpret_cast<const GridView*>(base + viewsAt);
}

void GpuTape::rebind(const GpuGridBinding& b) {
    const auto& grids = m_impl->grids;
    const auto it = std::find(grids.begin(), grids.end(), b.grid);
    if (it == grids.end()) return;  // not a grid of this tape
    GridView* slot = const_cast<GridView*>(m_impl->view.grids) + (it - grids.begin());
    SDFT_CUDA_CHECK(cudaMemcpy(slot, &b.view, sizeof(GridView), cudaMemcpyHostToDevice));
}

GpuTape::~GpuTape() = default;
GpuTape::GpuTape(GpuTape&&) noexcept = default;
GpuTape& GpuTape::operator=(GpuTape&&) noexcept = default;
const TapeView& GpuTape::view() const { return m_impl->view; }
size_t GpuTape::deviceBytes() const { return m_impl->bytes; }

}  // namespace sdft
