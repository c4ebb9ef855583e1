// The prepare step between a described scene and its render plan: every asset request (a grid
// file, a mesh baked to a grid, a subtree sampled into a grid) is loaded or baked once, in order
// (a subtree's own grids first), with progress on stderr; the pending grid nodes are replaced by
// the grids; the checks that needed their bounds run. Errors name the scene file and the JSON path
// of the request.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "sdftrace/field/grid.h"
#include "sdftrace/scene/scene.h"

namespace sdft {

// Grids by request key: a file or mesh used twice, in one scene or in several scenes prepared with
// the same cache (frames, viewers), is loaded and baked once.
class AssetCache {
  public:
    std::shared_ptr<const Grid> find(const std::string& key) const {
        auto it = m_grids.find(key);
        return it == m_grids.end() ? nullptr : it->second;
    }
    void insert(const std::string& key, std::shared_ptr<const Grid> grid) {
        if (!key.empty()) m_grids[key] = std::move(grid);
    }
    size_t size() const { return m_grids.size(); }
    // Drops every grid whose key is not in `keys` (the frames of an animation keep what the
    // current frame uses: a mesh sequence's past frames go, a rigid mesh stays).
    void keepOnly(const std::vector<std::string>& keys) {
        std::map<std::string, std::shared_ptr<const Grid>> kept;
        for (const std::string& k : keys)
            if (auto it = m_grids.find(k); it != m_grids.end()) kept.insert(*it);
        m_grids.swap(kept);
    }

  private:
    std::map<std::string, std::shared_ptr<const Grid>> m_grids;
};

struct PrepareOptions {
    bool progress = false;  // one line per asset on stderr, and the bakes' percentages
};

struct PrepareStats {
    size_t loaded = 0;  // grid files read
    size_t baked = 0;   // meshes and subtrees baked
    size_t cached = 0;  // requests served by the cache
};

PrepareStats prepareScene(Scene& scene, AssetCache& cache, const PrepareOptions& options = {});
// With a cache of its own.
PrepareStats prepareScene(Scene& scene, const PrepareOptions& options = {});

}  // namespace sdft
