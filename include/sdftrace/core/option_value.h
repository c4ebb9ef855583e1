// What a user-settable option accepts, apart from what it sets: its type, range or names, and
// the words that describe it. The render options (scene/render_options.h) and the bake options
// (bake/bake_options.h) are tables of rows that each carry one; parsing, range checks, error
// messages and the docs' "accepted" column come from here, so every front end (CLI flags, scene
// files, Python keywords, the viewer) says the same thing about the same option.
#pragma once

#include <initializer_list>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>

namespace sdft {

enum class OptionType { Bool, Int, Float, Choice };

struct OptionRange {
    double lo = 0, hi = 0;
    bool loOpen = false, hiOpen = false;  // excluded end points (floats)
    bool contains(double v) const {
        return (loOpen ? v > lo : v >= lo) && (hiOpen ? v < hi : v <= hi);
    }
};

// Numbers an option takes stay within +-1e9 (float geometry keeps about 7 digits; the scene
// files' limit, math/vec.h kMaxCoordinate).
inline constexpr double kMaxOptionMagnitude = 1e9;

// A value is held as a double: bools 0/1, choices their index, ints and floats themselves.
struct OptionValue {
    OptionType type;
    OptionRange range;                     // Int, Float
    const char* what;                      // Int, Float: "a distance" (error messages)
    std::span<const char* const> choices;  // Choice: the accepted words, in value order

    std::string accepted() const;      // "an integer in [1, 100000]", "true or false", ...
    std::string choiceList() const;    // "hard, soft, distributed, pcf, evsm"
    std::string show(double v) const;  // a value as the user writes it ("1.2", "true", "dda")
    // Range check of a number (Int: also integral); an error message or empty.
    std::string check(double v) const;
    // Parses text (a flag's value, a scene file's choice word) into `out`; an error message that
    // says what is accepted, empty on success.
    std::string parse(const std::string& text, double& out) const;
};

// A table row's member as its number and back (bools 0/1, enums their index).
template <class T>
double toOptionNumber(T v) {
    if constexpr (std::is_enum_v<T>)
        return static_cast<double>(static_cast<int>(v));
    else
        return static_cast<double>(v);
}

template <class T>
T fromOptionNumber(double v) {
    if constexpr (std::is_enum_v<T>)
        return static_cast<T>(static_cast<int>(v));
    else if constexpr (std::is_same_v<T, bool>)
        return v != 0;
    else
        return static_cast<T>(v);
}

// The get/set pair of a row whose member is `m` of `Settings` (nested members too: trace.omega).
#define SDFT_OPTION_MEMBER(Settings, m)                                   \
    .get = [](const Settings& s) { return ::sdft::toOptionNumber(s.m); }, \
    .set = [](Settings& s, double v) { s.m = ::sdft::fromOptionNumber<decltype(s.m)>(v); }

// A number as the docs write it: integers without a point, "inf", else the shortest form.
std::string showNumber(double v);
// A table cell: '|' escaped.
std::string markdownCell(const std::string& text);
// Text as code: `text`.
std::string markdownCode(std::string_view text);
// One row of a Markdown table: "| a | b |\n".
std::string markdownRow(std::initializer_list<std::string> cells);
// The main one of a row's CLI names, the first of "--res,--resolution".
std::string mainFlagOf(const char* flags);

}  // namespace sdft
