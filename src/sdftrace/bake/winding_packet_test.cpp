// Rows of points through the winding tree together (winding_packet.h) against the scalar
// windingNumberFast and windingInside, bit for bit, on a closed, an open and a thin mesh, with
// points near the surface, around holes and far away, in row lengths that are and are not
// multiples of the packet, at both SIMD levels; the float variant within 1e-5 of them.
#include "sdftrace/bake/winding_packet.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "sdftrace/bake/winding_number.h"
#include "sdftrace/exec/simd.h"
#include "sdftrace/io/mesh_io.h"

namespace sdft {
namespace {

TEST(WindingPacket, RowsEqualTheScalarEvaluation) {
    const SimdLevel level = simdLevel();
    for (const char* name : {"bunny_npm.obj", "elephant-with-holes.obj", "teapot.obj"}) {
        SCOPED_TRACE(name);
        const TriangleMesh mesh = loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + name);
        const WindingNumber winding(mesh);
        const WindingView w = winding.view();
        std::mt19937 rng(11);
        const Bounds3 b = mesh.bounds().expanded(0.2f * maxComponent(mesh.bounds().extent()));
        std::uniform_real_distribution<float> u(0, 1);
        std::uniform_int_distribution<size_t> vertex(0, mesh.positions.size() - 1);
        std::vector<Vec3> points;
        for (int i = 0; i < 1500; ++i) {
            // Half anywhere in the box, half within a few voxels of a vertex of the mesh.
            const Vec3 r(u(rng), u(rng), u(rng));
            points.push_back(i % 2 ? b.lo + b.extent() * r
                                   : mesh.positions[vertex(rng)] +
                                         (r - Vec3(0.5f)) * (0.02f * maxComponent(b.extent())));
        }
        for (const SimdLevel simd : {SimdLevel::Baseline, SimdLevel::Avx2}) {
            setSimdLevel(simd);
            for (const int n : {1, 7, 8, 13, 1500}) {
                std::vector<double> sums(static_cast<size_t>(n));
                std::vector<uint8_t> inside(static_cast<size_t>(n));
                windingNumberRow(w, points.data(), n, winding.beta(), sums.data());
                windingInsideRow(w, points.data(), n, winding.beta(), inside.data());
                int sumDiffer = 0, insideDiffer = 0;
                for (int i = 0; i < n; ++i) {
                    const double ref = winding.fast(points[static_cast<size_t>(i)]);
                    sumDiffer += std::memcmp(&ref, &sums[static_cast<size_t>(i)], 8) != 0 &&
                                 !(ref == 0 && sums[static_cast<size_t>(i)] == 0);
                    insideDiffer += (inside[static_cast<size_t>(i)] != 0) !=
                                    winding.inside(points[static_cast<size_t>(i)]);
                }
                EXPECT_EQ(sumDiffer, 0) << n << " points, " << simdLevelName(simdLevel());
                // Far terms in float: close to the double sums, not equal.
                std::vector<double> single(static_cast<size_t>(n));
                windingNumberRowFloat(w, points.data(), n, winding.beta(), single.data());
                double worst = 0;
                for (int i = 0; i < n; ++i)
                    worst = std::max(worst, std::fabs(single[static_cast<size_t>(i)] -
                                                      sums[static_cast<size_t>(i)]));
                EXPECT_LT(worst, 1e-5) << n << " points, " << simdLevelName(simdLevel());
                // Only the wanted points of the first 64, the others left as they were.
                const uint64_t wanted = 0x5a5a5a5a5a5a5a5aull;
                std::vector<double> some(static_cast<size_t>(n), -7.0);
                windingNumberRow(w, points.data(), n, winding.beta(), some.data(), wanted);
                for (int i = 0; i < n; ++i) {
                    const size_t k = static_cast<size_t>(i);
                    if (i < 64 && !((wanted >> i) & 1u))
                        EXPECT_EQ(some[k], -7.0) << i;
                    else
                        EXPECT_TRUE(some[k] == sums[k]) << i << " of " << n;
                }
                EXPECT_EQ(insideDiffer, 0) << n << " points, " << simdLevelName(simdLevel());
            }
        }
    }
    setSimdLevel(level);
}

}  // namespace
}  // namespace sdft
