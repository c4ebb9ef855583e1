// Fuzz target: the mesh path after the file reader. The input is a vertex and a triangle array
// (the shapes assimp hands over: any float, any index) that goes through the range check and the
// cleaning, then a small bake by a method and sign the input picks.
//
// Layout: u8 flags, u8 vertex count, u8 triangle count, then per vertex three coordinates (float32
// when flags bit 0 is set, else int8 / 16 so that most meshes are ordinary), then per triangle
// three u8 indices (taken modulo count + 2, so some are out of range).
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "fuzz_input.h"
#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/core/error.h"
#include "sdftrace/io/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace sdft;
    fuzz::limitMemoryForFuzzing();
    fuzz::Input in(data, size);
    const auto flags = in.take<uint8_t>();
    const int nv = in.take<uint8_t>() % 48, nt = in.take<uint8_t>() % 64;
    std::vector<Vec3> positions(nv);
    for (Vec3& p : positions)
        for (int a = 0; a < 3; ++a)
            p[a] = (flags & 1u) ? in.take<float>() : in.take<int8_t>() / 16.0f;
    std::vector<std::array<uint32_t, 3>> triangles(nt);
    for (auto& t : triangles)
        for (uint32_t& i : t) i = in.take<uint8_t>() % (nv + 2);
    MeshBakeOptions o;
    static constexpr MeshBakeMethod kMethods[] = {
        MeshBakeMethod::Exact, MeshBakeMethod::JumpFlood, MeshBakeMethod::Danielsson,
        MeshBakeMethod::SeparableEdt, MeshBakeMethod::Rtsdf};
    o.method = kMethods[(flags >> 1) % 5];
    o.sign = (flags & 0x10u) ? SignMethod::RayParity : SignMethod::WindingNumber;
    o.sampling.resolution = 8 + ((flags >> 5) & 1u) * 4;
    o.sampling.kind = (flags >> 4) & 1u ? GridKind::Dense : GridKind::Sparse;
    o.sampling.threads = 1;
    try {
        MeshReport report;
        const TriangleMesh mesh = cleanMesh(positions, triangles, report);
        const MeshBakeResult r = bakeMesh(mesh, o);
        const float v = r.grid.view().interpolate(r.grid.shape().bounds().center());
        if (std::isnan(v)) __builtin_trap();
    } catch (const InputError&) {
    }
    return 0;
}
