// A scene file over time (issue 16): its keyframed values (docs/scene-format.md, "Animation")
// evaluated at a time give the scene of that instant, described and prepared like a static one.
// Assets are requested per instant; an AssetCache shared across instants loads and bakes each
// distinct one once (a rigid mesh with keyframed transforms is baked once, a keyframed bake
// parameter bakes again where its value changes).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "sdftrace/scene/prepare_scene.h"
#include "sdftrace/scene/scene.h"

namespace sdft {

class AnimatedScene {
  public:
    // The scene file's text parsed and its keyframes validated; the scene itself is checked at its
    // start, at its end and at every key's time, so that a value out of range at a key is an
    // error now, not at that frame. Errors are InputErrors of one line; those of an instant end
    // with "(at time t s)".
    static AnimatedScene fromFile(const std::string& path);
    static AnimatedScene fromText(const std::string& text, const std::string& source,
                                  const std::string& baseDir = "");

    const SceneTime& time() const;
    // The scene at time t (seconds), its assets pending (prepareScene) or prepared.
    Scene describeAt(double t) const;
    // What preparing an instant did: its counts, and the cache keys of the assets it used.
    struct InstantAssets {
        PrepareStats stats;
        std::vector<std::string> keys;
    };
    Scene at(double t, AssetCache& cache, const PrepareOptions& options = {},
             InstantAssets* assets = nullptr) const;

  private:
    struct Impl;
    std::shared_ptr<const Impl> m_impl;
};

}  // namespace sdft
