// Skinned and morph-animated meshes through assimp (issue 16).
#include "sdftrace/io/mesh_animation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "sdftrace/core/error.h"
#include "sdftrace/math/vec.h"

namespace sdft {
namespace {

const std::string kTube = std::string(SDFT_SOURCE_DIR) + "/data/meshes/animated/bending_tube.gltf";
// Debian's assimp-testmodels (installed by scripts/install-deps.sh).
const std::string kAssimpModels = "/usr/share/assimp/models/";

Vec3 rotateZ(Vec3 p, float degrees) {
    const float a = radians(degrees), c = std::cos(a), s = std::sin(a);
    return {c * p.x - s * p.y, s * p.x + c * p.y, p.z};
}

// The tube of scripts/make-bending-tube.py: its root slides 1 unit along x over 2 s while its
// upper joint (y = 1) bends 90 degrees about z. Vertices held by one joint alone move rigidly with
// it; the bind pose is the file's static mesh.
TEST(MeshAnimation, ASkinnedTubeBendsAsItsJointsSay) {
    const AnimatedMesh tube = AnimatedMesh::load(kTube);
    ASSERT_EQ(tube.clips().size(), 1u);
    EXPECT_EQ(tube.clips()[0].name, "bend");
    EXPECT_NEAR(tube.clips()[0].duration, 2.0, 1e-9);
    EXPECT_TRUE(tube.clips()[0].skeletal);
    EXPECT_EQ(tube.clipIndex("bend"), 0);
    EXPECT_EQ(tube.clipIndex("walk"), -1);
    const TriangleMesh bind = loadMesh(kTube);
    const TriangleMesh start = tube.pose(0, 0);
    ASSERT_EQ(start.positions.size(), bind.positions.size());
    for (size_t i = 0; i < bind.positions.size(); ++i)
        EXPECT_LT(length(start.positions[i] - bind.positions[i]), 1e-6f) << i;
    for (double t : {0.5, 1.0, 1.7}) {
        const TriangleMesh posed = tube.pose(0, t);
        ASSERT_EQ(posed.positions.size(), bind.positions.size());
        EXPECT_TRUE(isWatertight(posed)) << "skinning keeps the surface closed";
        const Vec3 slide(static_cast<float>(t / 2), 0, 0);
        const float bend = static_cast<float>(45 * t);
        size_t lower = 0, upper = 0;
        for (size_t i = 0; i < bind.positions.size(); ++i) {
            const Vec3 b = bind.positions[i], p = posed.positions[i];
            if (b.y <= 0.75f) {
                EXPECT_LT(length(p - (b + slide)), 1e-5f) << "t " << t << ", vertex " << i;
                ++lower;
            } else if (b.y >= 1.25f) {
                const Vec3 joint = slide + Vec3(0, 1, 0);
                EXPECT_LT(length(p - (joint + rotateZ(b - Vec3(0, 1, 0), bend))), 1e-5f)
                    << "t " << t << ", vertex " << i;
                ++upper;
            }
        }
        EXPECT_GT(lower, 90u);
        EXPECT_GT(upper, 90u);
    }
    // Past its end a clip holds its last pose.
    const TriangleMesh end = tube.pose(0, 2), later = tube.pose(0, 7.5);
    for (size_t i = 0; i < end.positions.size(); ++i)
        EXPECT_EQ(length(end.positions[i] - later.positions[i]), 0.0f);
}

TEST(MeshAnimation, AFileWithoutAnimationHasNoClips) {
    const AnimatedMesh still =
        AnimatedMesh::load(std::string(SDFT_SOURCE_DIR) + "/data/meshes/bunny_npm.obj");
    EXPECT_TRUE(still.clips().empty());
    EXPECT_THROW(AnimatedMesh::load("/nonexistent/walk.gltf"), InputError);
}

// Third-party files: glTF morph targets (Khronos' AnimatedMorphCube) and a DirectX .x cylinder
// bent by four joints, two of which its hierarchy lacks (assimp's anim_test.x).
TEST(MeshAnimation, AssimpTestModelsPlay) {
    const std::string cube =
        kAssimpModels + "glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf";
    const std::string cylinder = kAssimpModels + "X/anim_test.x";
    if (!std::filesystem::exists(cube) || !std::filesystem::exists(cylinder))
        GTEST_SKIP() << "Debian's assimp-testmodels is not installed (scripts/install-deps.sh)";
    const AnimatedMesh morph = AnimatedMesh::load(cube);
    ASSERT_EQ(morph.clips().size(), 1u);
    EXPECT_TRUE(morph.clips()[0].morph);
    const float restTop = morph.pose(0, 0).bounds().hi.z;
    const float movedTop = morph.pose(0, 1.05).bounds().hi.z;
    EXPECT_NEAR(restTop, 1.0f, 1e-4f);  // the cube's base shape (its node scales it by 100)
    EXPECT_LT(movedTop, 0.0f) << "a target weighted in moves the top face down";
    EXPECT_TRUE(isWatertight(morph.pose(0, 1.05)));

    const AnimatedMesh bent = AnimatedMesh::load(cylinder);
    ASSERT_EQ(bent.clips().size(), 1u);
    const TriangleMesh rest = bent.pose(0, 0), end = bent.pose(0, bent.clips()[0].duration);
    ASSERT_EQ(rest.positions.size(), end.positions.size());
    float moved = 0;
    for (size_t i = 0; i < rest.positions.size(); ++i) {
        moved = std::max(moved, length(end.positions[i] - rest.positions[i]));
        if (rest.positions[i].y < -4.9f) {  // the base ring, held by the root joint
            EXPECT_LT(length(end.positions[i] - rest.positions[i]), 0.05f) << i;
        }
    }
    EXPECT_GT(moved, 0.5f);
    EXPECT_TRUE(isWatertight(end));
}

}  // namespace
}  // namespace sdft
