#include "sdftrace/scene/prepare_scene.h"

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

namespace sdft {

namespace {

// The tree with its pending grid nodes replaced by the loaded grids (the material a pending node
// carries stays on it); subtrees without pending grids are shared, not copied. `done` maps each
// rewritten node to its copy, so a node shared within the tree (or between a subtree request and
// the tree) is rewritten once.
NodePtr substitute(const NodePtr& n, const std::vector<std::shared_ptr<const Grid>>& grids,
                   std::unordered_map<const Node*, NodePtr>& done) {
    if (!hasPendingAssets(*n)) return n;
    auto it = done.find(n.get());
    if (it != done.end()) return it->second;
    auto copy = std::make_shared<Node>(*n);
    if (n->kind == NodeKind::Grid) {
        SDFT_CHECK(n->asset >= 0 && static_cast<size_t>(n->asset) < grids.size());
        copy->grid = grids[static_cast<size_t>(n->asset)];
        SDFT_CHECK(copy->grid != nullptr);  // requests come before the nodes that use them
        copy->asset = -1;
    }
    for (NodePtr& c : copy->children) c = substitute(c, grids, done);
    done.emplace(n.get(), copy);
    return copy;
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

// Loads or bakes one request; file and bake errors get the request's JSON path.
std::shared_ptr<const Grid> loadAsset(const AssetRequest& q, const NodePtr& subtree,
                                      bool progress) {
    try {
        switch (q.kind) {
            case AssetRequest::Kind::GridFile:
                return std::make_shared<const Grid>(loadGridFile(q.path));
            case AssetRequest::Kind::Mesh: {
                MeshBakeOptions bake = q.bake;
                bake.progress = progress;
                return std::make_shared<const Grid>(bakeMesh(loadMesh(q.path), bake).grid);
            }
            case AssetRequest::Kind::Subtree:
                return std::make_shared<const Grid>(sampleSubtree(q, subtree));
        }
    } catch (const InputError& e) {
        const std::string m = e.what();
        // Subtree errors already carry the path.
        throw InputError(m.rfind(q.where, 0) == 0 ? m : q.where + ": " + m);
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

PrepareStats prepareScene(Scene& scene, AssetCache& cache, const PrepareOptions& options) {
    PrepareStats stats;
    std::vector<std::shared_ptr<const Grid>> grids(scene.assets.size());
    std::unordered_map<const Node*, NodePtr> done;
    for (size_t i = 0; i < scene.assets.size(); ++i) {
        const AssetRequest& q = scene.assets[i];
        if ((grids[i] = cache.find(q.key))) {
            ++stats.cached;
            continue;
        }
        if (options.progress) {
            std::fprintf(stderr, "sdftrace: asset %zu/%zu: %s\n", i + 1, scene.assets.size(),
                         describe(q).c_str());
        }
        const NodePtr subtree = q.subtree ? substitute(q.subtree, grids, done) : nullptr;
        grids[i] = loadAsset(q, subtree, options.progress);
        cache.insert(q.key, grids[i]);
        ++(q.kind == AssetRequest::Kind::GridFile ? stats.loaded : stats.baked);
    }
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
