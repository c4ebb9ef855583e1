#include "sdftrace/io/mesh_io.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <numeric>
#include <tuple>

#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/io/mesh_readers.h"
#include "sdftrace/io/text_cursor.h"

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
    // Weld exact duplicates (bitwise-equal positions; -0 and +0 compare equal too), by sorting
    // the positions' bit patterns: each run of equal ones becomes the vertex of its first record.
    struct Key {
        uint32_t bits[3];
        uint32_t index;
        bool operator<(const Key& o) const {
            return std::tie(bits[0], bits[1], bits[2], index) <
                   std::tie(o.bits[0], o.bits[1], o.bits[2], o.index);
        }
        bool samePosition(const Key& o) const {
            return bits[0] == o.bits[0] && bits[1] == o.bits[1] && bits[2] == o.bits[2];
        }
    };
    std::vector<Key> order(positions.size());
    for (size_t i = 0; i < positions.size(); ++i) {
        Vec3 p = positions[i];
        for (int a = 0; a < 3; ++a)
            if (p[a] == 0.0f) p[a] = 0.0f;  // one zero
        std::memcpy(order[i].bits, &p, sizeof order[i].bits);
        order[i].index = static_cast<uint32_t>(i);
    }
    tbb::parallel_sort(order.begin(), order.end());
    std::vector<uint32_t> remap(positions.size());
    std::vector<Vec3> welded;
    for (size_t i = 0; i < order.size(); ++i) {
        if (i == 0 || !order[i].samePosition(order[i - 1])) {
            Vec3 p;
            std::memcpy(&p, order[i].bits, sizeof order[i].bits);
            welded.push_back(p);
        }
        remap[order[i].index] = static_cast<uint32_t>(welded.size() - 1);
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
    // Duplicate (either winding) triangles, boundary edges, components. Counted by sorting (a
    // std::map of 3M edges took 2 s of a million-triangle mesh's 2.4 s load).
    std::vector<std::array<uint32_t, 3>> keys(mesh.triangles.size());
    std::vector<uint64_t> edges(3 * mesh.triangles.size());
    std::vector<uint32_t> parent(mesh.positions.size());
    std::iota(parent.begin(), parent.end(), 0u);
    for (size_t i = 0; i < mesh.triangles.size(); ++i) {
        const auto& t = mesh.triangles[i];
        keys[i] = t;
        std::sort(keys[i].begin(), keys[i].end());
        for (int e = 0; e < 3; ++e) {
            uint32_t a = t[e], b = t[(e + 1) % 3];
            edges[3 * i + e] = static_cast<uint64_t>(std::min(a, b)) << 32 | std::max(a, b);
            parent[findRoot(parent, a)] = static_cast<uint32_t>(findRoot(parent, b));
        }
    }
    tbb::parallel_sort(keys.begin(), keys.end());
    r.duplicateTriangles =
        keys.size() - static_cast<size_t>(std::unique(keys.begin(), keys.end()) - keys.begin());
    tbb::parallel_sort(edges.begin(), edges.end());
    for (size_t i = 0; i < edges.size();) {
        size_t j = i + 1;
        while (j < edges.size() && edges[j] == edges[i]) ++j;
        r.boundaryEdges += j - i == 1;
        i = j;
    }
    for (uint32_t v = 0; v < parent.size(); ++v) r.components += findRoot(parent, v) == v;
    return mesh;
}

namespace {

// The long tail of formats (glTF/GLB, Collada, FBX, .x, ...) through assimp, its scene
// validated (aiProcess_ValidateDataStructure: counts, indices and pointers checked before any
// post-processing step reads them) and its arrays checked again as they are copied.
MeshArrays readWithAssimp(const std::string& path) {
    precheckForAssimp(path);
    Assimp::Importer importer;
    // Triangulate polygons and flatten the node hierarchy so every mesh is in world space. The
    // importer may split vertices per face corner; welding by exact position is ours (cleanMesh).
    const aiScene* scene =
        importer.ReadFile(path, aiProcess_ValidateDataStructure | aiProcess_Triangulate |
                                    aiProcess_PreTransformVertices);
    if (!scene && std::string(importer.GetErrorString()).find("bad_alloc") != std::string::npos) {
        // assimp turns std::bad_alloc into an error string; the allocation guard of the CLI
        // throws it for any single allocation over the memory budget.
        throw InputError(path + ": cannot read mesh: it needs more memory than the budget of " +
                         formatBytes(memoryBudgetBytes()) +
                         " (raise --max-memory, or simplify the mesh)");
    }
    if (!scene || !scene->mRootNode || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
        std::string why = importer.GetErrorString();
        std::replace(why.begin(), why.end(), '\n', ' ');
        throw InputError(path + ": cannot read mesh (" + TextCursor::printable(why) +
                         "); accepted: OBJ, PLY, STL, OFF, glTF/GLB and the other formats of "
                         "assimp");
    }
    MeshArrays out;
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
        const aiMesh* mesh = scene->mMeshes[m];
        if (!mesh || (mesh->mNumVertices && !mesh->mVertices) || (mesh->mNumFaces && !mesh->mFaces))
            throw InputError(path + ": cannot read mesh (mesh " + std::to_string(m) +
                             " has no vertex or face arrays)");
        const auto base = static_cast<uint32_t>(out.positions.size());
        for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
            const aiVector3D& p = mesh->mVertices[v];
            out.positions.push_back({p.x, p.y, p.z});
        }
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const aiFace& face = mesh->mFaces[f];
            if (face.mNumIndices != 3 || !face.mIndices) continue;  // points and lines
            for (int k = 0; k < 3; ++k)
                if (face.mIndices[k] >= mesh->mNumVertices)
                    throw InputError(path + ": mesh " + std::to_string(m) + ", face " +
                                     std::to_string(f) + " uses vertex " +
                                     std::to_string(face.mIndices[k]) + " of " +
                                     std::to_string(mesh->mNumVertices));
            out.triangles.push_back(
                {base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
        }
    }
    return out;
}

}  // namespace

TriangleMesh loadMesh(const std::string& path, MeshReport* report) {
    if (!std::filesystem::exists(path))
        throw InputError(path + ": cannot open mesh file (does it exist?)");
    std::error_code ec;
    if (std::filesystem::file_size(path, ec) == 0 && !ec)
        throw InputError(path + ": the mesh file is empty");
    MeshArrays arrays = readWithinBudget(path, [&] {
        const MeshReader own = ownMeshReader(path);
        return own ? own(path) : readWithAssimp(path);
    });
    for (size_t v = 0; v < arrays.positions.size(); ++v) {
        const Vec3& p = arrays.positions[v];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            throw InputError(path + ": vertex " + std::to_string(v) + " is not finite");
    }
    MeshReport local;
    MeshReport& r = report ? *report : local;
    // Before cleaning: its area tests would call a mesh out of range degenerate.
    if (std::string problem = meshRangeProblem({arrays.positions, arrays.triangles});
        !problem.empty())
        throw InputError(path + ": " + problem);
    TriangleMesh mesh = cleanMesh(arrays.positions, arrays.triangles, r);
    if (mesh.triangles.empty())
        throw InputError(path + ": the mesh has no (non-degenerate) triangles");
    return mesh;
}

}  // namespace sdft
