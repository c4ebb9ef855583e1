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

}  // namespace

struct GpuTape::Impl {
    void* buffer = nullptr;
    size_t bytes = 0;
    TapeView view;
    ~Impl() {
        if (buffer) cudaFree(buffer);
    }
};

GpuTape::GpuTape(const Tape& tape) : m_impl(std::make_unique<Impl>()) {
    requireGpu("GPU tape");
    Packer pack;
    const std::span<const Instr> instrs = tape.instructions();
    const std::span<const float> consts = tape.constants();
    const size_t instrAt = pack.add(instrs.data(), instrs.size_bytes());
    const size_t constAt = pack.add(consts.data(), consts.size_bytes());
    // Each grid's arrays, then the array of their (relocated) views.
    struct GridPieces {
        GridView view;
        size_t samples = 0, tilePage = 0, tileSkip = 0, flags = 0, blockData = 0, blockSamples = 0,
               blockNeighbors = 0, cellMasks = 0, blockSkip = 0, texcoords = 0, tileLipschitz = 0,
               blockLipschitz = 0;
    };
    std::vector<GridPieces> grids;
    for (const auto& g : tape.grids()) {
        GridPieces p;
        p.view = g->view();
        p.samples = pack.add(g->samples());
        p.tilePage = pack.add(g->tilePage());
        p.tileSkip = pack.add(g->tileSkip());
        p.flags = pack.add(g->flags());
        p.blockData = pack.add(g->blockData());
        p.blockSamples = pack.add(g->blockSamples());
        p.blockNeighbors = pack.add(g->blockNeighbors());
        p.cellMasks = pack.add(g->cellMasks());
        p.blockSkip = pack.add(g->blockSkip());
        p.texcoords = pack.add(g->texcoords());
        p.tileLipschitz = pack.add(g->tileLipschitz());
        p.blockLipschitz = pack.add(g->blockLipschitz());
        grids.push_back(p);
    }
    // The views' offsets are known now; their addresses once the buffer is allocated.
    const size_t viewsAt = pack.add(nullptr, 0);
    pack.bytes().resize(viewsAt + grids.size() * sizeof(GridView));
    std::vector<unsigned char>& bytes = pack.bytes();
    SDFT_CUDA_CHECK(cudaMalloc(&m_impl->buffer, bytes.size() ? bytes.size() : 1));
    m_impl->bytes = bytes.size();
    const unsigned char* base = static_cast<const unsigned char*>(m_impl->buffer);
    for (size_t i = 0; i < grids.size(); ++i) {
        GridPieces& p = grids[i];
        const Grid& g = *tape.grids()[i];
        relocate(p.view.samples, g.samples(), p.samples, base);
        relocate(p.view.tilePage, g.tilePage(), p.tilePage, base);
        relocate(p.view.tileSkip, g.tileSkip(), p.tileSkip, base);
        relocate(p.view.flags, g.flags(), p.flags, base);
        relocate(p.view.blockData, g.blockData(), p.blockData, base);
        relocate(p.view.blockSamples, g.blockSamples(), p.blockSamples, base);
        relocate(p.view.blockNeighbors, g.blockNeighbors(), p.blockNeighbors, base);
        relocate(p.view.cellMasks, g.cellMasks(), p.cellMasks, base);
        relocate(p.view.blockSkip, g.blockSkip(), p.blockSkip, base);
        relocate(p.view.texcoords, g.texcoords(), p.texcoords, base);
        relocate(p.view.tileLipschitz, g.tileLipschitz(), p.tileLipschitz, base);
        relocate(p.view.blockLipschitz, g.blockLipschitz(), p.blockLipschitz, base);
        std::memcpy(bytes.data() + viewsAt + i * sizeof(GridView), &p.view, sizeof(GridView));
    }
    SDFT_CUDA_CHECK(cudaMemcpy(m_impl->buffer, bytes.data(), bytes.size(), cudaMemcpyHostToDevice));
    TapeView& v = m_impl->view;
    v = tape.view();
    v.instrs = reinterpret_cast<const Instr*>(base + instrAt);
    v.consts = reinterpret_cast<const float*>(base + constAt);
    v.grids = grids.empty() ? nullptr : reinterpret_cast<const GridView*>(base + viewsAt);
}

GpuTape::~GpuTape() = default;
GpuTape::GpuTape(GpuTape&&) noexcept = default;
GpuTape& GpuTape::operator=(GpuTape&&) noexcept = default;
const TapeView& GpuTape::view() const { return m_impl->view; }
size_t GpuTape::deviceBytes() const { return m_impl->bytes; }

}  // namespace sdft
