#include "sdftrace/io/mesh_io.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <numeric>
#include <unordered_map>

#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"

namespace sdft {

std::string MeshReport::summary() const {
    char buf[400];
    std::snprintf(
        buf, sizeof buf,
        "%zu triangles and %zu vertex records read, welded by exact position to %zu vertices; "
        "dropped %zu unused vertices and %zu degenerate triangles; %zu duplicate triangles, "
        "%zu boundary edges, %zu components",
        trianglesRead, verticesRead, verticesRead - weldedVertices, unusedVertices,
        degenerateTriangles, duplicateTriangles, boundaryEdges, components);
    return buf;
}

namespace {

struct Vec3Hash {
    size_t operator()(const Vec3& v) const {
        uint32_t b[3];
        std::memcpy(b, &v, sizeof b);
        return (static_cast<size_t>(b[0]) * 73856093u) ^ (static_cast<size_t>(b[1]) * 19349663u) ^
               (static_cast<size_t>(b[2]) * 83492791u);
    }
};
struct Vec3Eq {
    bool operator()(const Vec3& a, const Vec3& b) const {
        return a.x == b.x && a.y == b.y && a.z == b.z;
    }
};

size_t findRoot(std::vector<uint32_t>& parent, uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
}

}  // namespace

TriangleMesh cleanMesh(const std::vector<Vec3>& positions,
                       const std::vector<std::array<uint32_t, 3>>& triangles, MeshReport& r) {
    r.verticesRead = positions.size();
    r.trianglesRead = triangles.size();
    for (size_t i = 0; i < triangles.size(); ++i)
        for (uint32_t v : triangles[i])
            if (v >= positions.size())
                throw InputError("mesh: triangle " + std::to_string(i) + " uses vertex " +
                                 std::to_string(v) + ", but there are " +
                                 std::to_string(positions.size()) +
                                 " vertices (accepted: indices below the vertex count)");
    // Weld exact duplicates (bitwise-equal positions; -0 and +0 compare equal too).
    std::unordered_map<Vec3, uint32_t, Vec3Hash, Vec3Eq> index;
    std::vector<uint32_t> remap(positions.size());
    std::vector<Vec3> welded;
    for (size_t i = 0; i < positions.size(); ++i) {
        Vec3 p = positions[i];
        for (int a = 0; a < 3; ++a)
            if (p[a] == 0.0f) p[a] = 0.0f;  // one zero
        auto [it, inserted] = index.emplace(p, static_cast<uint32_t>(welded.size()));
        if (inserted) welded.push_back(p);
        remap[i] = it->second;
    }
    r.weldedVertices = positions.size() - welded.size();
    // Drop degenerate triangles: a repeated vertex or (numerically) zero area.
    std::vector<std::array<uint32_t, 3>> kept;
    for (const auto& t : triangles) {
        std::array<uint32_t, 3> u = {remap[t[0]], remap[t[1]], remap[t[2]]};
        Vec3 n = cross(welded[u[1]] - welded[u[0]], welded[u[2]] - welded[u[0]]);
        if (u[0] == u[1] || u[1] == u[2] || u[0] == u[2] || !(dot(n, n) > 0)) {
            ++r.degenerateTriangles;
            continue;
        }
        kept.push_back(u);
    }
    // Drop unused vertices.
    std::vector<uint32_t> used(welded.size(), UINT32_MAX);
    TriangleMesh mesh;
    for (auto& t : kept)
        for (auto& v : t) {
            if (used[v] == UINT32_MAX) {
                used[v] = static_cast<uint32_t>(mesh.positions.size());
                mesh.positions.push_back(welded[v]);
            }
            v = used[v];
        }
    r.unusedVertices = welded.size() - mesh.positions.size();
    mesh.triangles = std::move(kept);
    // Duplicate (either winding) triangles, boundary edges, components.
    std::map<std::array<uint32_t, 3>, int> seen;
    std::map<std::pair<uint32_t, uint32_t>, int> edges;
    std::vector<uint32_t> parent(mesh.positions.size());
    std::iota(parent.begin(), parent.end(), 0u);
    for (const auto& t : mesh.triangles) {
        std::array<uint32_t, 3> key = t;
        std::sort(key.begin(), key.end());
        if (seen[key]++ > 0) ++r.duplicateTriangles;
        for (int e = 0; e < 3; ++e) {
            uint32_t a = t[e], b = t[(e + 1) % 3];
            edges[{std::min(a, b), std::max(a, b)}]++;
            parent[findRoot(parent, a)] = static_cast<uint32_t>(findRoot(parent, b));
        }
    }
    for (const auto& [e, count] : edges) r.boundaryEdges += count == 1;
    for (uint32_t v = 0; v < parent.size(); ++v) r.components += findRoot(parent, v) == v;
    return mesh;
}

TriangleMesh loadMesh(const std::string& path, MeshReport* report) {
    if (!std::filesystem::exists(path))
        throw InputError(path + ": cannot open mesh file (does it exist?)");
    Assimp::Importer importer;
    // Triangulate polygons and flatten the node hierarchy so every mesh is in world space. The
    // importer may split vertices per face corner; welding by exact position is ours (cleanMesh).
    const aiScene* scene =
        importer.ReadFile(path, aiProcess_Triangulate | aiProcess_PreTransformVertices);
    if (!scene && std::string(importer.GetErrorString()).find("bad_alloc") != std::string::npos) {
        // assimp turns std::bad_alloc into an error string; the allocation guard of the CLI
        // throws it for any single allocation over the memory budget.
        throw InputError(path + ": cannot read mesh: it needs more memory than the budget of " +
                         formatBytes(memoryBudgetBytes()) +
                         " (raise --max-memory, or simplify the mesh)");
    }
    if (!scene || !scene->mRootNode || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
        throw InputError(path + ": cannot read mesh (" + std::string(importer.GetErrorString()) +
                         "); accepted: OBJ, PLY, STL, OFF, glTF");
    }
    std::vector<Vec3> positions;
    std::vector<std::array<uint32_t, 3>> triangles;
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
        const aiMesh* mesh = scene->mMeshes[m];
        uint32_t base = static_cast<uint32_t>(positions.size());
        for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
            const aiVector3D& p = mesh->mVertices[v];
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
                throw InputError(path + ": vertex " + std::to_string(base + v) + " is not finite");
            }
            positions.push_back({p.x, p.y, p.z});
        }
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const aiFace& face = mesh->mFaces[f];
            if (face.mNumIndices != 3) continue;  // points and lines
            triangles.push_back(
                {base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
        }
    }
    MeshReport local;
    MeshReport& r = report ? *report : local;
    // Before cleaning: its area tests would call a mesh out of range degenerate.
    if (std::string problem = meshRangeProblem({positions, triangles}); !problem.empty())
        throw InputError(path + ": " + problem);
    TriangleMesh mesh = cleanMesh(positions, triangles, r);
    if (mesh.triangles.empty())
        throw InputError(path + ": the mesh has no (non-degenerate) triangles");
    return mesh;
}

}  // namespace sdft
