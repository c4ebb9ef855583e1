#include "sdftrace/scene/animated_scene.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

#include "scene_json.h"

namespace sdft {

struct AnimatedScene::Impl {
    nlohmann::json root;
    std::vector<JsonTrack> tracks;
    SceneTime time;
    std::string source, baseDir;
};

namespace {
std::string atTime(double t) {
    char buf[64];
    std::snprintf(buf, sizeof buf, " (at time %g s)", t);
    return buf;
}
}  // namespace

AnimatedScene AnimatedScene::fromText(const std::string& text, const std::string& source,
                                      const std::string& baseDir) {
    auto impl = std::make_shared<Impl>();
    impl->root = readSceneJson(text, source);
    impl->tracks = findKeyframedValues(impl->root, source);
    impl->time = sceneTimeOf(impl->root, impl->tracks, source);
    impl->source = source;
    impl->baseDir = baseDir;
    AnimatedScene scene;
    scene.m_impl = impl;
    // Checked at the span's ends and at every key (distinct times, in order); a scene with more
    // than kCheckedTimes distinct key times is checked at that many of them, evenly spread, so
    // that loading stays quick (every frame is checked again when it is rendered).
    constexpr size_t kCheckedTimes = 256;
    std::set<double> times{impl->time.start, impl->time.end};
    for (const JsonTrack& track : impl->tracks)
        for (const Keyframe& key : track.track.keys()) times.insert(key.time);
    const std::vector<double> all(times.begin(), times.end());
    const size_t step = (all.size() + kCheckedTimes - 1) / kCheckedTimes;
    for (size_t i = 0; i < all.size(); i += step) scene.describeAt(all[i]);
    if ((all.size() - 1) % step != 0) scene.describeAt(all.back());
    return scene;
}

AnimatedScene AnimatedScene::fromFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw InputError(path + ": cannot open scene file (does it exist and is it readable?)");
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw InputError(path + ": cannot read scene file");
    return fromText(text.str(), path, std::filesystem::path(path).parent_path().string());
}

const SceneTime& AnimatedScene::time() const { return m_impl->time; }

namespace {
// Runs f for the instant t of an animated scene; its InputErrors then name the time.
template <class F>
void atInstant(bool animated, double t, F f) {
    try {
        f();
    } catch (const InputError& e) {
        if (!animated) throw;
        throw InputError(e.what() + atTime(t));
    }
}
}  // namespace

Scene AnimatedScene::describeAt(double t) const {
    const Impl& s = *m_impl;
    Scene scene;
    atInstant(!s.tracks.empty(), t, [&] {
        scene = s.tracks.empty()
                    ? describeSceneJson(s.root, s.source, s.baseDir, t)
                    : describeSceneJson(valuesAt(s.root, s.tracks, t), s.source, s.baseDir, t);
    });
    scene.time = s.time;
    return scene;
}

Scene AnimatedScene::at(double t, AssetCache& cache, const PrepareOptions& options,
                        InstantAssets* assets) const {
    Scene scene = describeAt(t);
    InstantAssets local;
    InstantAssets& out = assets ? *assets : local;
    out.keys.clear();
    for (const AssetRequest& q : scene.assets) out.keys.push_back(q.key);
    atInstant(!m_impl->tracks.empty(), t, [&] { out.stats = prepareScene(scene, cache, options); });
    return scene;
}

}  // namespace sdft
