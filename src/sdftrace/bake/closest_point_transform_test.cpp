#include "sdftrace/bake/closest_point_transform.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/io/mesh_io.h"
#include "test_meshes.h"

namespace sdft {
namespace {

// Every sample against Embree's closest-point query: equal up to float rounding (the transform
// works in voxel units, Embree in world units), on closed, open and messy meshes, including
// samples far from the mesh and on grids that cut the mesh.
void expectMatchesBvh(const TriangleMesh& mesh, int resolution, float paddingVoxels,
                      float maxRatio) {
    SampleOptions o;
    o.resolution = resolution;
    o.kind = GridKind::Dense;
    o.paddingVoxels = paddingVoxels;
    const GridShape shape = gridShapeFor(mesh.bounds(), o);
    std::vector<float> cpt(shape.vertexCount());
    ClosestPointTransformStats st;
    closestPointTransform(mesh, shape, cpt.data(), &st);
    MeshBvh bvh(mesh);
    size_t i = 0, bad = 0;
    float worst = 0;
    for (int z = 0; z < shape.vertices(2); ++z)
        for (int y = 0; y < shape.vertices(1); ++y)
            for (int x = 0; x < shape.vertices(0); ++x, ++i) {
                const float ref =
                    bvh.closestDistance(shape.origin + Vec3(x, y, z) * shape.voxelSize);
                const float err = std::fabs(cpt[i] - ref);
                worst = std::max(worst, err);
                // float rounding of coordinates up to `resolution` voxels
                if (!(err <= 1e-5f * resolution * shape.voxelSize)) ++bad;
            }
    EXPECT_EQ(bad, 0u) << "worst error " << worst / shape.voxelSize << " voxels";
    // The regions overlap only a few times over on smooth closed meshes: the point of the
    // method. Open boundaries (half-slab regions) and noise (wide wedges) raise it.
    EXPECT_LT(double(st.evaluations) / shape.vertexCount(), maxRatio);
    EXPECT_GT(st.faces, 0u);
    EXPECT_GE(st.maxDistance, 0.0f);
}

TEST(ClosestPointTransform, MatchesBvhOnClosedMeshes) {
    expectMatchesBvh(testing::icosphere(3), 40, 10, 12);
    expectMatchesBvh(testing::torusMesh(1.0f, 0.35f, 48, 24), 48, 8, 12);
    expectMatchesBvh(testing::boxMesh({1.0f, 0.5f, 0.25f}), 32, 6, 12);
}

TEST(ClosestPointTransform, MatchesBvhOnOpenAndScannedMeshes) {
    for (const char* name : {"elephant-with-holes.obj", "teapot.obj", "suzanne.obj"}) {
        SCOPED_TRACE(name);
        expectMatchesBvh(loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + name), 40, 4,
                         100);
    }
}

// A grid that covers only part of the mesh: regions are cut to it, values stay exact.
TEST(ClosestPointTransform, GridCuttingTheMesh) {
    TriangleMesh mesh = testing::torusMesh(1.0f, 0.35f, 40, 20);
    GridShape shape;
    shape.cells[0] = 24;
    shape.cells[1] = 12;
    shape.cells[2] = 10;
    shape.voxelSize = 0.05f;
    shape.origin = {0.2f, -0.3f, -0.25f};
    std::vector<float> cpt(shape.vertexCount());
    closestPointTransform(mesh, shape, cpt.data());
    MeshBvh bvh(mesh);
    size_t i = 0;
    for (int z = 0; z <= shape.cells[2]; ++z)
        for (int y = 0; y <= shape.cells[1]; ++y)
            for (int x = 0; x <= shape.cells[0]; ++x, ++i)
                ASSERT_NEAR(cpt[i],
                            bvh.closestDistance(shape.origin + Vec3(x, y, z) * shape.voxelSize),
                            1e-5f)
                    << x << " " << y << " " << z;
}

// Degenerate inputs: one triangle, a flat sheet of coplanar triangles (every inner edge's region
// is a sheet), and a grid wholly beside the mesh.
TEST(ClosestPointTransform, SingleTrianglesFlatSheetsAndDistantGrids) {
    TriangleMesh one;
    one.positions = {{0, 0, 0}, {1, 0.2f, 0.1f}, {0.3f, 0.9f, -0.2f}};
    one.triangles = {{0, 1, 2}};
    TriangleMesh sheet;
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) sheet.positions.push_back({i * 0.3f, j * 0.3f, 0.0f});
    for (uint32_t j = 0; j < 3; ++j)
        for (uint32_t i = 0; i < 3; ++i) {
            const uint32_t v = j * 4 + i;
            sheet.triangles.push_back({v, v + 1, v + 5});
            sheet.triangles.push_back({v, v + 5, v + 4});
        }
    for (const TriangleMesh* mesh : {&one, &sheet}) {
        MeshBvh bvh(*mesh);
        for (Vec3 origin : {Vec3(-0.5f, -0.5f, -0.5f), Vec3(2.0f, 1.5f, 0.7f)}) {
            GridShape shape;
            shape.cells[0] = 20;
            shape.cells[1] = 18;
            shape.cells[2] = 16;
            shape.voxelSize = 0.1f;
            shape.origin = origin;
            std::vector<float> cpt(shape.vertexCount());
            closestPointTransform(*mesh, shape, cpt.data());
            size_t i = 0;
            for (int z = 0; z <= shape.cells[2]; ++z)
                for (int y = 0; y <= shape.cells[1]; ++y)
                    for (int x = 0; x <= shape.cells[0]; ++x, ++i)
                        ASSERT_NEAR(cpt[i],
                                    bvh.closestDistance(origin + Vec3(x, y, z) * shape.voxelSize),
                                    1e-5f)
                            << x << " " << y << " " << z;
        }
    }
}

}  // namespace
}  // namespace sdft
