// The CPU's jump flooding sweeps rows (jump_flood.cpp, built for SSE2 and AVX2) where the GPU runs
// jumpFloodVertex per vertex (jump_flood_step.h): they must keep the same points, ties included.
#include "sdftrace/bake/jump_flood.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "sdftrace/bake/jump_flood_step.h"
#include "sdftrace/exec/simd.h"

namespace sdft {
namespace {

// Every pass of `variant` by jumpFloodVertex, vertex by vertex.
std::vector<Vec3> perVertex(const GridShape& s, std::vector<Vec3> seed, JfaVariant variant) {
    std::vector<Vec3> next(seed.size());
    for (int off : jumpFloodOffsets(s, variant)) {
        for (int k = 0; k < s.vertices(2); ++k)
            for (int j = 0; j < s.vertices(1); ++j)
                for (int i = 0; i < s.vertices(0); ++i)
                    next[vertexIndex(s, i, j, k)] = jumpFloodVertex(s, seed.data(), i, j, k, off);
        seed.swap(next);
    }
    return seed;
}

// Sparse random seeds (most vertices hold none) on a grid of unequal sides, and seeds on a lattice
// whose points are equidistant from many vertices (ties), through every variant.
TEST(JumpFlood, RowSweepKeepsThePerVertexStepsPoints) {
    GridShape s;
    s.cells[0] = 37, s.cells[1] = 21, s.cells[2] = 13;
    s.voxelSize = 0.1f;
    s.origin = Vec3(-1.3f, 0.2f, 0.7f);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0, 1);
    for (const bool lattice : {false, true}) {
        std::vector<Vec3> seed(s.vertexCount(), Vec3(kNoSeed));
        for (int k = 0; k < s.vertices(2); ++k)
            for (int j = 0; j < s.vertices(1); ++j)
                for (int i = 0; i < s.vertices(0); ++i) {
                    const Vec3 p = vertexPosition(s, i, j, k);
                    if (lattice ? (i % 6 == 0 && j % 5 == 0 && k % 4 == 0) : u(rng) < 0.01f)
                        seed[vertexIndex(s, i, j, k)] =
                            lattice ? p : p + Vec3(u(rng), u(rng), u(rng)) * 0.05f;
                }
        const SimdLevel level = simdLevel();
        for (const SimdLevel simd : {SimdLevel::Baseline, SimdLevel::Avx2}) {
            setSimdLevel(simd);  // the AVX2 row where the CPU has it
            for (JfaVariant v :
                 {JfaVariant::Plain, JfaVariant::OnePlusJfa, JfaVariant::JfaPlusTwo}) {
                const std::vector<Vec3> rows = jumpFlood(s, seed, v), ref = perVertex(s, seed, v);
                ASSERT_EQ(rows.size(), ref.size());
                EXPECT_EQ(std::memcmp(rows.data(), ref.data(), ref.size() * sizeof(Vec3)), 0)
                    << (lattice ? "lattice" : "random") << ", variant " << static_cast<int>(v)
                    << ", " << simdLevelName(simdLevel());
                EXPECT_NE(rows[0].x, kNoSeed);  // flooded everywhere
            }
        }
        setSimdLevel(level);
    }
}

}  // namespace
}  // namespace sdft
