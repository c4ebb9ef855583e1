// The steps of describing a scene file, for the static and the animated scene (internal to the
// scene module): its text to JSON, its time span, and JSON without keyframes to a Scene.
#pragma once

#include <string>
#include <vector>

#include "json_reader.h"
#include "keyframed_json.h"
#include "sdftrace/scene/scene.h"

namespace sdft {

// Parsed JSON; malformed text is an InputError naming `source`.
nlohmann::json readSceneJson(const std::string& text, const std::string& source);

// The "animation" block of `root` (validated), else the span of the tracks' keys.
SceneTime sceneTimeOf(const nlohmann::json& root, const std::vector<JsonTrack>& tracks,
                      const std::string& source);

// The scene of JSON whose keyframed values have been replaced by values (valuesAt), at `time`
// seconds (where meshes that "play" their own animation are posed).
Scene describeSceneJson(const nlohmann::json& root, const std::string& source,
                        const std::string& baseDir, double time = 0);

}  // namespace sdft
