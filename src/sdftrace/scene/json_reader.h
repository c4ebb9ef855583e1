// Typed, validated reads from a JSON object with the JSON path of every value, so each error names
// the file, the path, what was wrong and what is accepted (internal to the scene module).
#pragma once

#include <functional>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sdftrace/core/error.h"
#include "sdftrace/core/option_value.h"
#include "sdftrace/math/vec.h"

namespace sdft::json_reader {

using Json = nlohmann::json;

class Reader {
  public:
    Reader(const Json& value, std::string source, std::string path)
        : m_value(value), m_source(std::move(source)), m_path(std::move(path)) {}

    const Json& value() const { return m_value; }
    const std::string& path() const { return m_path; }
    const std::string& source() const { return m_source; }
    Reader child(const std::string& key) const {
        return {m_value.at(key), m_source, m_path + "/" + key};
    }
    Reader element(size_t i) const {
        return {m_value.at(i), m_source, m_path + "/" + std::to_string(i)};
    }
    bool has(const std::string& key) const { return m_value.is_object() && m_value.contains(key); }

    [[noreturn]] void fail(const std::string& message) const {
        throw InputError(m_source + ": " + shortPath(m_path.empty() ? "/" : m_path) + ": " +
                         message);
    }
    [[noreturn]] void failKey(const std::string& key, const std::string& message) const {
        throw InputError(location(key) + ": " + message);
    }
    // "<file>: <JSON path>/<key>", the start of an error about that key.
    std::string location(const std::string& key) const {
        return m_source + ": " + shortPath(m_path + "/" + key);
    }
    // A JSON path as messages show it: whole, or its start and end around "/…/" when very long.
    static std::string shortPath(const std::string& path) {
        if (path.size() <= 160) return path;
        const size_t head = path.find('/', 60), tail = path.rfind('/', path.size() - 60);
        if (head == std::string::npos || tail == std::string::npos || head >= tail) return path;
        return path.substr(0, head) + "/\u2026" + path.substr(tail);
    }

    void requireObject(const char* what) const;
    void requireArray(const char* what) const;
    // Rejects keys outside `allowed` (typos would otherwise be silently ignored).
    void allowKeys(std::initializer_list<const char*> allowed) const;
    void allowKeys(const std::vector<std::string>& allowed) const;

    // A finite number satisfying `ok`, described by `accepted` ("a positive number").
    float number(const std::string& key, const std::function<bool(double)>& ok,
                 const std::string& accepted) const;
    float number(const std::string& key, float fallback, const std::function<bool(double)>& ok,
                 const std::string& accepted) const;
    int integer(const std::string& key, int fallback, int lo, int hi) const;
    bool boolean(const std::string& key, bool fallback) const;
    std::string string(const std::string& key) const;
    std::string string(const std::string& key, const std::string& fallback) const;
    // Three finite numbers; each must satisfy `ok`.
    Vec3 vec3(const std::string& key, const std::function<bool(double)>& ok = nullptr,
              const std::string& accepted = "") const;
    Vec3 vec3(const std::string& key, Vec3 fallback,
              const std::function<bool(double)>& ok = nullptr,
              const std::string& accepted = "") const;

  private:
    const Json& m_value;
    std::string m_source;
    std::string m_path;
};

// A number as messages show it (6 significant digits).
std::string show(double v);

inline bool positive(double v) { return v > 0; }
inline bool nonNegative(double v) { return v >= 0; }
inline bool anyFinite(double) { return true; }

// The value of an option table's row (core/option_value.h) at `key`, as the row's number (bools
// 0/1, choices their index): a choice by its word (a choice of numbers, like a block size of 4 or
// 8, also as a number), a number checked against the row's range; else an error naming the key.
double optionValue(const Reader& r, const char* key, const OptionValue& option);

}  // namespace sdft::json_reader
