// Keyframed values in a scene's JSON (docs/scene-format.md, "Animation"; internal to the scene
// module): wherever a scene file takes a number or an array of numbers, it may give an object
//   {"keyframes": [{"time": 0, "value": v0}, {"time": 2, "value": v1}, ...],
//    "interpolation": "linear" | "smooth" | "step", "extrapolation": "clamp" | "loop"}
// The scene at time t is the same JSON with every such object replaced by its value at t, so the
// scene readers, their checks and their messages (JSON paths) are the static scene's.
#pragma once

#include <string>
#include <vector>

#include "json_reader.h"
#include "sdftrace/scene/keyframes.h"

namespace sdft {

struct JsonTrack {
    nlohmann::json::json_pointer where;  // the value's place in the scene's JSON
    KeyframeTrack track;
    bool scalar = true;     // a number (false: an array of numbers)
    bool integers = false;  // every key's value is a JSON integer: integral results stay integers
};

// Every keyframed value of `root`, validated: one-line errors "<source>: <JSON path>: ...".
std::vector<JsonTrack> findKeyframedValues(const nlohmann::json& root, const std::string& source);

// `root` with every track replaced by its value at time t.
nlohmann::json valuesAt(const nlohmann::json& root, const std::vector<JsonTrack>& tracks, double t);

}  // namespace sdft
