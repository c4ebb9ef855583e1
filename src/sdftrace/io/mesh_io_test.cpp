// Real meshes (data/meshes, facts from its README) through the loader and its cleaning.
#include "sdftrace/io/mesh_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "sdftrace/core/error.h"

namespace sdft {
namespace {

std::string meshPath(const std::string& name) {
    return std::string(SDFT_SOURCE_DIR) + "/data/meshes/" + name;
}

TEST(MeshIo, ClosedBunnyLoadsWatertight) {
    MeshReport r;
    TriangleMesh m = loadMesh(meshPath("bunny_npm.obj"), &r);
    EXPECT_EQ(m.positions.size(), 1839u);
    EXPECT_EQ(m.triangles.size(), 3674u);
    EXPECT_EQ(r.boundaryEdges, 0u);
    EXPECT_EQ(r.components, 1u);
    EXPECT_EQ(r.degenerateTriangles, 0u);
}

TEST(MeshIo, TeapotNeedsWeldingAndIsOpen) {
    MeshReport r;
    TriangleMesh m = loadMesh(meshPath("teapot.obj"), &r);
    // 3,644 vertices in the file, 403 of them exact duplicates.
    EXPECT_EQ(m.positions.size(), 3644u - 403u);
    EXPECT_GE(r.weldedVertices, 403u);
    EXPECT_EQ(r.boundaryEdges, 160u);
    EXPECT_EQ(r.components, 3u);
    EXPECT_EQ(m.triangles.size() + r.degenerateTriangles, 6320u);
}

TEST(MeshIo, SuzanneReportsItsDuplicateTriangle) {
    MeshReport r;
    TriangleMesh m = loadMesh(meshPath("suzanne.obj"), &r);
    EXPECT_EQ(r.trianglesRead, 968u);
    EXPECT_EQ(r.duplicateTriangles, 1u);  // the back-to-back pair
    EXPECT_LE(m.positions.size(), 507u);  // 507 in the file, exact duplicates welded
    EXPECT_GT(r.boundaryEdges, 0u);       // the eyes' open rims
}

TEST(MeshIo, ElephantWithHolesHasItsBoundary) {
    MeshReport r;
    TriangleMesh m = loadMesh(meshPath("elephant-with-holes.obj"), &r);
    EXPECT_EQ(m.triangles.size(), 4463u);
    EXPECT_EQ(r.boundaryEdges, 1353u);
    EXPECT_FALSE(r.summary().empty());
}

TEST(MeshIo, CleaningDropsDegenerateTrianglesAndUnusedVertices) {
    std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {2, 0, 0}, {5, 5, 5}};
    // a real triangle; one using a welded copy of vertex 1 twice; one collinear (zero area)
    std::vector<std::array<uint32_t, 3>> t = {{0, 1, 2}, {1, 3, 2}, {0, 1, 4}};
    MeshReport r;
    TriangleMesh m = cleanMesh(p, t, r);
    EXPECT_EQ(r.weldedVertices, 1u);
    EXPECT_EQ(r.degenerateTriangles, 2u);
    EXPECT_EQ(m.triangles.size(), 1u);
    EXPECT_EQ(m.positions.size(), 3u);
    EXPECT_EQ(r.unusedVertices, 2u);  // (2,0,0) and (5,5,5)
    EXPECT_EQ(r.boundaryEdges, 3u);
}

TEST(MeshIo, BadFilesAreRejectedByName) {
    std::string dir = std::filesystem::temp_directory_path().string() + "/sdftrace-mesh-" +
                      std::to_string(::getpid());
    std::filesystem::create_directories(dir);
    auto expectError = [](const std::string& path, const std::string& fragment) {
        try {
            loadMesh(path);
            ADD_FAILURE() << "accepted " << path;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
        }
    };
    expectError(dir + "/missing.obj", "cannot open");
    std::ofstream(dir + "/garbage.stl") << "this is not a mesh at all";
    expectError(dir + "/garbage.stl", "not ascii STL");
    std::ofstream(dir + "/points.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    expectError(dir + "/points.obj", "");
    std::ofstream(dir + "/flat.obj") << "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n";
    expectError(dir + "/flat.obj", "no (non-degenerate) triangles");
    // assimp is never left to guess a format from the bytes (some of its importers read damaged
    // ones out of bounds): an extension no importer claims is refused, and so is a file that
    // none of the importers of its extension recognises (glTF 1 and 2 both claim .gltf).
    const std::string gltf = R"({"asset": {"version": "2.0"}, "meshes": []})";
    std::ofstream(dir + "/scene.anim") << gltf;
    expectError(dir + "/scene.anim", "unknown mesh format '.anim' (accepted: .obj, .ply");
    std::ofstream(dir + "/scene.mymesh") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    expectError(dir + "/scene.mymesh", "unknown mesh format '.mymesh'");
    std::ofstream(dir + "/not.gltf") << R"({"neither": "glTF 1 nor 2"})";
    expectError(dir + "/not.gltf", "no importer of the extension recognises its content");
    // glTF references are held to their arrays before assimp follows them (it dereferences
    // what is missing or out of range); a skin without inverse bind matrices is refused by name.
    std::ofstream(dir + "/node.gltf") << R"({"asset": {"version": "2.0"}, "nodes": [{"mesh": 3}]})";
    expectError(dir + "/node.gltf", "glTF: /nodes/0/mesh is 3, not an index of meshes (0 of them)");
    std::ofstream(dir + "/skin.gltf")
        << R"({"asset": {"version": "2.0"}, "nodes": [{}], "skins": [{"joints": [0]}]})";
    expectError(dir + "/skin.gltf", "glTF: /skins/0 has no inverseBindMatrices");
    std::ofstream(dir + "/anim.gltf")
        << R"({"asset": {"version": "2.0"}, "animations": [{"channels": [{"sampler": 1,
              "target": {"node": 0, "path": "rotation"}}], "samplers": []}]})";
    expectError(dir + "/anim.gltf", "/animations/0/channels/0/sampler is 1");
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace sdft
