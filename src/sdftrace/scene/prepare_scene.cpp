#include "sdftrace/scene/prepare_scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <unordered_map>

#include "parse_node.h"
#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/bake/texture_coords.h"
#include "sdftrace/core/error.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/io/grid_file.h"
#include "sdftrace/io/mesh_io.h"
#include "sdftrace/scene/mesh_accel.h"

namespace sdft {

namespace {

// The tree with its pending grid nodes replaced by the loaded grids (the material a pending node
// carries stays on it); a node none of whose descendants was pending is returned as it is, not
// copied. `done` remembers every node visited, so a node shared within the tree (or between a
// subtree request and the tree) is visited once.
NodePtr substitute(const NodePtr& n, const std::vector<std::shared_ptr<const Grid>>& grids,
                   std::unordered_map<const Node*, NodePtr>& done) {
    auto it = done.find(n.get());
    if (it != done.end()) return it->second;
    NodePtr out = n;
    if (n->kind == NodeKind::Grid && !n->grid) {
        SDFT_CHECK(n->asset >= 0 && static_cast<size_t>(n->asset) < grids.size());
        SDFT_CHECK(grids[static_cast<size_t>(n->asset)]);  // requests precede their users
        auto copy = std::make_shared<Node>(*n);
        copy->grid = grids[static_cast<size_t>(n->asset)];
        copy->asset = -1;
        out = copy;
    } else {
        std::vector<NodePtr> children;
        bool changed = false;
        for (const NodePtr& c : n->children) {
            children.push_back(substitute(c, grids, done));
            changed |= children.back() != c;
        }
        if (changed) {
            auto copy = std::make_shared<Node>(*n);
            copy->children = std::move(children);
            out = copy;
        }
    }
    done.emplace(n.get(), out);
    return out;
}

std::string describe(const AssetRequest& q) {
    switch (q.kind) {
        case AssetRequest::Kind::GridFile:
            return "loading " + q.path;
        case AssetRequest::Kind::Mesh:
            return "baking " + q.path + " at " + std::to_string(q.bake.sampling.resolution) +
                   " cells";
        case AssetRequest::Kind::Subtree:
            return "sampling a subtree at " + std::to_string(q.sampling.resolution) + " cells" +
                   (q.texcoords ? " with texture coordinates" : "");
    }
    return "";
}

Grid sampleSubtree(const AssetRequest& q, const NodePtr& subtree) {
    if (!boundedField(subtree)) throw InputError(q.where + ": " + kUnbounded);
    const Tape tape = compileTape(subtree, {.boundsCulling = false});
    Grid grid = sampleGrid(tape, tape.bounds(), q.sampling);
    if (q.texcoords)
        bakeTexcoords(
            grid, [&tape](Vec3 p) { return tape.eval(p); }, *q.texcoords);
    return grid;
}

// The pose of a played mesh (AssetRequest::play): its clip chosen by name or number, its time
// wrapped into the clip or clamped to it.
// A played mesh's clip (checked), by name or number.
int playedClip(const AssetRequest& q, const AnimatedMesh& mesh) {
    const AssetRequest::Play& p = *q.play;
    if (mesh.clips().empty())
        throw InputError(p.where + ": " + q.path +
                         " has no skeletal or morph animation (assimp found none); remove "
                         "\"play\", or give a glTF, Collada, FBX or .x file with one");
    int clip = p.clipIndex;
    if (!p.clip.empty()) {
        clip = mesh.clipIndex(p.clip);
        if (clip < 0)
            throw InputError(p.where + "/animation: no animation named '" + p.clip + "' in " +
                             q.path + "; it has " + mesh.clipList());
    } else if (static_cast<size_t>(clip) >= mesh.clips().size()) {
        throw InputError(p.where + "/animation: animation " + std::to_string(clip) + " of " +
                         q.path + ", which has " + std::to_string(mesh.clips().size()) + ": " +
                         mesh.clipList());
    }
    return clip;
}

TriangleMesh posedMesh(const AssetRequest& q, AssetCache& cache) {
    const AssetRequest::Play& p = *q.play;
    const AnimatedMesh& mesh = cache.animatedMesh(q.path);
    const int clip = playedClip(q, mesh);
    const double duration = mesh.clips()[static_cast<size_t>(clip)].duration;
    double t = p.seconds;
    if (p.loop && duration > 0) t -= duration * std::floor(t / duration);
    return mesh.pose(clip, std::clamp(t, 0.0, duration));
}

// Where a played mesh goes over its whole clip (its poses at 33 evenly spaced times), so that the
// grid RTSDF regenerates it in holds every frame.
Bounds3 clipBounds(const AssetRequest& q, AssetCache& cache) {
    const AnimatedMesh& mesh = cache.animatedMesh(q.path);
    const int clip = playedClip(q, mesh);
    const double duration = mesh.clips()[static_cast<size_t>(clip)].duration;
    Bounds3 b;
    for (int k = 0; k <= 32; ++k) b = unite(b, mesh.pose(clip, duration * k / 32).bounds());
    return b;
}

// Loads or bakes one request; file and bake errors get the request's JSON path.
std::shared_ptr<const Grid> loadAsset(const AssetRequest& q, const NodePtr& subtree,
                                      const PrepareOptions& options, AssetCache& cache,
                                      std::shared_ptr<const TriangleMesh>& triangles) {
    const bool progress = options.progress;
    try {
        switch (q.kind) {
            case AssetRequest::Kind::GridFile:
                return sceneGrid(loadGridFile(q.path), options.gapLattice);
            case AssetRequest::Kind::Mesh: {
                MeshBakeOptions bake = q.bake;
                bake.progress = progress;
                auto loaded = std::make_shared<const TriangleMesh>(q.play ? posedMesh(q, cache)
                                                                          : loadMesh(q.path));
                triangles = loaded;
                const TriangleMesh& mesh = *loaded;
                if (q.dynamic == AssetRequest::Dynamic::Rtsdf) {
                    // RTSDF §2.5.1: one grid for all frames, over the first frame's bounds (a
                    // played mesh's: its whole clip's) widened by a quarter each way so that the
                    // mesh may move and deform in it.
                    RtsdfHistory& h = cache.rtsdfHistory(q.where);
                    h.alpha = q.alpha;
                    if (h.frames == 0) {
                        Bounds3 b = q.play ? clipBounds(q, cache) : mesh.bounds();
                        const Vec3 margin = b.extent() * 0.25f;
                        h.shape = gridShapeFor({b.lo - margin, b.hi + margin}, bake.sampling);
                    }
                    bake.shape = h.shape;
                    bake.rtsdf.history = &h;
                    // Every block kept, as RTSDF's 3D textures cover their volume: beyond the
                    // mask the grid holds the coarse SDF's distances, which SDF soft shadows
                    // (k h / t) need (a narrow band leaves only lower bounds there, read as near
                    // misses). A complete block grid (Grid::completeFromDense), whose layout the
                    // next frame refreshes. Its samples are unclamped, so its blocks share the
                    // global Lipschitz bound (Grid::computeLocalLipschitz's floor of background
                    // / (B h) keeps the local one for narrow bands).
                    bake.sampling.bandVoxels = 1e6f;
                    MeshBakeResult baked =
                        options.bakeMesh ? options.bakeMesh(mesh, bake) : bakeMesh(mesh, bake);
                    h.gridOnDevice = baked.onDevice;
                    // On the GPU, from the second frame on, the values stay in the device grid
                    // and the last host grid stands in (MeshBakeOptions::gpuResident).
                    if (baked.onDevice) {
                        SDFT_CHECK(h.grid);
                        return h.grid;
                    }
                    auto grid = std::make_shared<const Grid>(std::move(baked.grid));
                    h.grid = grid;
                    return grid;
                }
                return sceneGrid(
                    (options.bakeMesh ? options.bakeMesh(mesh, bake) : bakeMesh(mesh, bake)).grid,
                    options.gapLattice);
            }
            case AssetRequest::Kind::Subtree:
                return sceneGrid(sampleSubtree(q, subtree), options.gapLattice);
        }
    } catch (const InputError& e) {
        const std::string m = e.what();
        // Subtree and play errors already carry the path.
        const bool located = m.rfind(q.where, 0) == 0 || (q.play && m.rfind(q.play->where, 0) == 0);
        throw InputError(located ? m : q.where + ": " + m);
    }
    return nullptr;
}

// Copies of a repetition's child must not overlap; checked once the child's grids are loaded.
void checkRepeats(const Scene& scene, const std::vector<std::shared_ptr<const Grid>>& grids,
                  std::unordered_map<const Node*, NodePtr>& done) {
    for (const RepeatCheck& c : scene.repeatChecks) {
        const NodePtr child = substitute(c.child, grids, done);
        if (std::string error = repeatOverlap(nodeBounds(*child), c.cell, c.count); !error.empty())
            throw InputError(c.where + "/cell: " + error);
    }
}

}  // namespace

std::shared_ptr<const Grid> sceneGrid(Grid grid, bool gapLattice) {
    if (gapLattice) grid.computeGapLattice();
    return std::make_shared<const Grid>(std::move(grid));
}

std::shared_ptr<const MeshAccel> AssetCache::meshAccel(
    const std::shared_ptr<const TriangleMesh>& mesh) {
    dropUnheldAccels();
    auto it = m_accels.find(mesh.get());
    if (it != m_accels.end() && it->second->meshPointer() == mesh) return it->second;
    auto accel = std::make_shared<const MeshAccel>(mesh);
    bool held = false;  // only meshes the cache holds stay (their accels hold them in turn)
    for (const auto& [key, m] : m_meshes) held = held || m == mesh;
    if (held) m_accels[mesh.get()] = accel;
    return accel;
}

void AssetCache::dropUnheldAccels() {
    for (auto it = m_accels.begin(); it != m_accels.end();) {
        bool held = false;
        for (const auto& [key, m] : m_meshes) held = held || m.get() == it->first;
        it = held ? std::next(it) : m_accels.erase(it);
    }
}

void shareMeshAccels(Scene& scene, AssetCache& cache) {
    if (!scene.settings.primaryTriangles) return;
    for (const auto& [grid, mesh] : scene.meshes) {
        // Posed on the GPU with its grid: nothing on the host.
        if (!deviceStateOf(scene.deviceGrids, grid))
            scene.meshAccels[mesh.get()] = cache.meshAccel(mesh);
    }
}

PrepareStats prepareScene(Scene& scene, AssetCache& cache, const PrepareOptions& options) {
    PrepareStats stats;
    std::vector<std::shared_ptr<const Grid>> grids(scene.assets.size());
    std::unordered_map<const Node*, NodePtr> done;
    for (size_t i = 0; i < scene.assets.size(); ++i) {
        const AssetRequest& q = scene.assets[i];
        if ((grids[i] = cache.find(q.key))) {
            if (auto mesh = cache.findMesh(q.key)) scene.meshes[grids[i].get()] = mesh;
            ++stats.cached;
            continue;
        }
        if (options.progress) {
            std::fprintf(stderr, "sdftrace: asset %zu/%zu: %s\n", i + 1, scene.assets.size(),
                         describe(q).c_str());
        }
        const NodePtr subtree = q.subtree ? substitute(q.subtree, grids, done) : nullptr;
        std::shared_ptr<const TriangleMesh> triangles;
        grids[i] = loadAsset(q, subtree, options, cache, triangles);
        cache.insert(q.key, grids[i]);
        cache.insertMesh(q.key, triangles);
        if (triangles) scene.meshes[grids[i].get()] = triangles;
        if (q.dynamic == AssetRequest::Dynamic::Rtsdf) {
            const RtsdfHistory& h = cache.rtsdfHistory(q.where);
            if (h.gridOnDevice) scene.deviceGrids.push_back({grids[i].get(), h.device});
        }
        ++(q.kind == AssetRequest::Kind::GridFile ? stats.loaded : stats.baked);
    }
    shareMeshAccels(scene, cache);
    checkRepeats(scene, grids, done);
    if (scene.root) scene.root = substitute(scene.root, grids, done);
    scene.assets.clear();
    scene.repeatChecks.clear();
    SDFT_CHECK(scene.prepared());
    return stats;
}

PrepareStats prepareScene(Scene& scene, const PrepareOptions& options) {
    AssetCache cache;
    return prepareScene(scene, cache, options);
}

}  // namespace sdft
