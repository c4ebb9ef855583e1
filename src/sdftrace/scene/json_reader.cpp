#include "json_reader.h"

#include <cmath>
#include <sstream>

namespace sdft::json_reader {

namespace {
std::string typeName(const Json& v) {
    if (v.is_number()) return "a number";
    if (v.is_string()) return "a string";
    if (v.is_boolean()) return "a boolean";
    if (v.is_array()) return "an array";
    if (v.is_object()) return "an object";
    if (v.is_null()) return "null";
    return "something else";
}
// Scene geometry is computed in float, which keeps about 7 digits: larger numbers lose the
// surface (squared distances overflow, rays step past it).
constexpr double kMaxNumber = kMaxCoordinate;
const char* const tooLarge = "; numbers in scene files must lie within +-1e9";

}  // namespace

std::string show(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

void Reader::requireObject(const char* what) const {
    if (!m_value.is_object())
        fail(std::string("expected ") + what + " (a JSON object), got " + typeName(m_value));
}

void Reader::requireArray(const char* what) const {
    if (!m_value.is_array())
        fail(std::string("expected ") + what + " (a JSON array), got " + typeName(m_value));
}

void Reader::allowKeys(std::initializer_list<const char*> allowed) const {
    allowKeys(std::vector<std::string>(allowed.begin(), allowed.end()));
}

void Reader::allowKeys(const std::vector<std::string>& allowed) const {
    for (auto it = m_value.begin(); it != m_value.end(); ++it) {
        bool ok = false;
        for (const std::string& a : allowed) ok = ok || it.key() == a;
        if (ok) continue;
        std::string list;
        for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
        failKey(it.key(), "unknown key; accepted here: " + list);
    }
}

float Reader::number(const std::string& key, const std::function<bool(double)>& ok,
                     const std::string& accepted) const {
    if (!has(key)) fail("missing required key '" + key + "' (" + accepted + ")");
    const Json& v = m_value.at(key);
    if (!v.is_number()) failKey(key, "expected " + accepted + ", got " + typeName(v));
    double d = v.get<double>();
    if (!std::isfinite(d) || std::fabs(d) > kMaxNumber)
        failKey(key, "expected " + accepted + ", got " + show(d) + tooLarge);
    if (!ok(d)) failKey(key, "expected " + accepted + ", got " + show(d));
    return static_cast<float>(d);
}

float Reader::number(const std::string& key, float fallback, const std::function<bool(double)>& ok,
                     const std::string& accepted) const {
    return has(key) ? number(key, ok, accepted) : fallback;
}

int Reader::integer(const std::string& key, int fallback, int lo, int hi) const {
    if (!has(key)) return fallback;
    const Json& v = m_value.at(key);
    std::string accepted = "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    if (!v.is_number()) failKey(key, "expected " + accepted + ", got " + typeName(v));
    double d = v.get<double>();
    if (!std::isfinite(d) || d != std::floor(d) || d < lo || d > hi) {
        failKey(key, "expected " + accepted + ", got " + show(d));
    }
    return static_cast<int>(d);
}

bool Reader::boolean(const std::string& key, bool fallback) const {
    if (!has(key)) return fallback;
    const Json& v = m_value.at(key);
    if (!v.is_boolean()) failKey(key, "expected true or false, got " + typeName(v));
    return v.get<bool>();
}

std::string Reader::string(const std::string& key) const {
    if (!has(key)) fail("missing required key '" + key + "' (a string)");
    const Json& v = m_value.at(key);
    if (!v.is_string()) failKey(key, "expected a string, got " + typeName(v));
    return v.get<std::string>();
}

std::string Reader::string(const std::string& key, const std::string& fallback) const {
    return has(key) ? string(key) : fallback;
}

Vec3 Reader::vec3(const std::string& key, const std::function<bool(double)>& ok,
                  const std::string& accepted) const {
    std::string what = "an array of 3 numbers" + (accepted.empty() ? "" : " (" + accepted + ")");
    if (!has(key)) fail("missing required key '" + key + "' (" + what + ")");
    const Json& v = m_value.at(key);
    if (!v.is_array() || v.size() != 3)
        failKey(key, "expected " + what + ", got " + typeName(v) +
                         (v.is_array() ? " of " + std::to_string(v.size()) : ""));
    Vec3 out;
    for (int i = 0; i < 3; ++i) {
        if (!v[i].is_number())
            failKey(key + "/" + std::to_string(i), "expected a number, got " + typeName(v[i]));
        double d = v[i].get<double>();
        if (!std::isfinite(d) || std::fabs(d) > kMaxNumber)
            failKey(key + "/" + std::to_string(i), "got " + show(d) + tooLarge);
        if (ok && !ok(d))
            failKey(key + "/" + std::to_string(i), "expected " + accepted + ", got " + show(d));
        out[i] = static_cast<float>(d);
    }
    return out;
}

Vec3 Reader::vec3(const std::string& key, Vec3 fallback, const std::function<bool(double)>& ok,
                  const std::string& accepted) const {
    return has(key) ? vec3(key, ok, accepted) : fallback;
}

double optionValue(const Reader& r, const char* key, const OptionValue& option) {
    double v = 0;
    switch (option.type) {
        case OptionType::Bool:
            return r.boolean(key, false) ? 1 : 0;
        case OptionType::Choice: {
            const Json& j = r.value().at(key);
            const std::string text = j.is_number() ? showNumber(j.get<double>()) : r.string(key);
            if (std::string error = option.parse(text, v); !error.empty()) r.failKey(key, error);
            return v;
        }
        case OptionType::Int:
        case OptionType::Float:
            v = r.number(key, anyFinite, option.accepted());
            if (std::string error = option.check(r.value().at(key).get<double>()); !error.empty())
                r.failKey(key, error);
            return r.value().at(key).get<double>();
    }
    return v;
}

}  // namespace sdft::json_reader
