#include "keyframed_json.h"

#include <cmath>

namespace sdft {

using json_reader::Json;
using json_reader::Reader;
using json_reader::show;

namespace {

constexpr size_t kMaxComponents = 16;  // the longest array a scene key takes is 3 (or 4) numbers

// The key's value as components; fails unless it is a finite number or 1-16 finite numbers.
std::vector<double> keyValue(const Reader& key, bool& scalar, bool& integer) {
    const Json& v = key.value().at("value");
    const char* accepted =
        "a number or an array of 1 to 16 numbers (the value a scene key takes at that time)";
    std::vector<double> out;
    auto take = [&](const Json& x, const std::string& where) {
        if (!x.is_number()) key.failKey(where, std::string("expected ") + accepted);
        const double d = x.get<double>();
        if (!std::isfinite(d) || std::fabs(d) > kMaxCoordinate)
            key.failKey(where, "expected numbers within +-1e9, got " + show(d));
        integer = integer && x.is_number_integer();
        out.push_back(d);
    };
    integer = true;
    if (v.is_number()) {
        scalar = true;
        take(v, "value");
    } else if (v.is_array() && !v.empty() && v.size() <= kMaxComponents) {
        scalar = false;
        for (size_t i = 0; i < v.size(); ++i) take(v[i], "value/" + std::to_string(i));
    } else {
        key.failKey("value", std::string("expected ") + accepted);
    }
    return out;
}

JsonTrack parseTrack(const Reader& r, const Json::json_pointer& where) {
    r.allowKeys({"keyframes", "interpolation", "extrapolation"});
    const std::string interp = r.string("interpolation", "linear");
    Interpolation interpolation = Interpolation::Linear;
    if (interp == "smooth")
        interpolation = Interpolation::Smooth;
    else if (interp == "step")
        interpolation = Interpolation::Step;
    else if (interp != "linear")
        r.failKey("interpolation",
                  "unknown interpolation '" + interp + "'; accepted: linear, smooth, step");
    const std::string extra = r.string("extrapolation", "clamp");
    Extrapolation extrapolation = Extrapolation::Clamp;
    if (extra == "loop")
        extrapolation = Extrapolation::Loop;
    else if (extra != "clamp")
        r.failKey("extrapolation", "unknown extrapolation '" + extra + "'; accepted: clamp, loop");
    Reader list = r.child("keyframes");
    list.requireArray("a list of keyframes {\"time\": t, \"value\": v} in increasing time");
    if (list.value().empty()) list.fail("expected at least one keyframe");
    std::vector<Keyframe> keys;
    bool scalar = true, integers = true;
    for (size_t i = 0; i < list.value().size(); ++i) {
        Reader key = list.element(i);
        key.requireObject("a keyframe {\"time\": t, \"value\": v}");
        key.allowKeys({"time", "value"});
        if (!key.has("value")) key.fail("missing required key 'value'");
        const double time = key.number("time", json_reader::anyFinite, "a time in seconds");
        bool keyScalar = true, keyIntegers = true;
        std::vector<double> value = keyValue(key, keyScalar, keyIntegers);
        if (!keys.empty()) {
            if (!(time > keys.back().time))
                key.failKey("time", "time " + show(time) + " is not after the previous key's " +
                                        show(keys.back().time) +
                                        "; keyframes must be in strictly increasing time");
            if (keyScalar != scalar || value.size() != keys.back().value.size())
                key.failKey("value",
                            "expected a value of the same shape as the first key's (" +
                                (scalar ? std::string("a number")
                                        : std::to_string(keys.front().value.size()) + " numbers") +
                                ")");
        }
        scalar = keyScalar;
        integers = integers && keyIntegers;
        keys.push_back({time, std::move(value)});
    }
    return {where, KeyframeTrack(std::move(keys), interpolation, extrapolation), scalar, integers};
}

// Valid scenes nest objects at most 256 deep (an object and its children list per level).
constexpr int kMaxDepth = 1024;

void collect(const Reader& r, const Json::json_pointer& where, std::vector<JsonTrack>& out,
             int depth) {
    const Json& v = r.value();
    if (depth > kMaxDepth && (v.is_object() || v.is_array()))
        r.fail("JSON nested deeper than " + std::to_string(kMaxDepth) +
               " levels (scene objects nest at most 256 deep)");
    if (v.is_object()) {
        if (v.contains("keyframes")) {
            out.push_back(parseTrack(r, where));
            return;
        }
        for (auto it = v.begin(); it != v.end(); ++it)
            collect(r.child(it.key()), where / it.key(), out, depth + 1);
    } else if (v.is_array()) {
        for (size_t i = 0; i < v.size(); ++i) collect(r.element(i), where / i, out, depth + 1);
    }
}

}  // namespace

std::vector<JsonTrack> findKeyframedValues(const Json& root, const std::string& source) {
    std::vector<JsonTrack> tracks;
    collect(Reader(root, source, ""), Json::json_pointer(), tracks, 0);
    return tracks;
}

Json valuesAt(const Json& root, const std::vector<JsonTrack>& tracks, double t) {
    Json out = root;
    std::vector<double> v;
    for (const JsonTrack& track : tracks) {
        v.resize(track.track.components());
        track.track.evaluate(t, v.data());
        auto value = [&](double d) -> Json {
            if (track.integers && d == std::floor(d) && std::fabs(d) < 9e15)
                return static_cast<long long>(d);
            return d;
        };
        if (track.scalar) {
            out[track.where] = value(v[0]);
        } else {
            Json a = Json::array();
            for (double d : v) a.push_back(value(d));
            out[track.where] = a;
        }
    }
    return out;
}

}  // namespace sdft
