#include "sdftrace/core/option_value.h"

#include <cmath>
#include <cstdlib>
#include <sstream>

namespace sdft {

std::string showNumber(double v) {
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    if (v == std::floor(v) && std::fabs(v) < 1e15) return std::to_string(static_cast<long long>(v));
    std::ostringstream s;
    s << v;
    return s.str();
}

std::string markdownCell(const std::string& text) {
    std::string out;
    for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
    return out;
}

std::string markdownCode(std::string_view text) {
    std::string c = "`";
    c += text;
    c += '`';
    return c;
}

std::string markdownRow(std::initializer_list<std::string> cells) {
    std::string row;
    for (const std::string& cell : cells) {
        row += "| ";
        row += cell;
        row += ' ';
    }
    row += "|\n";
    return row;
}

std::string mainFlagOf(const char* flags) {
    const std::string f = flags;
    return f.substr(0, f.find(','));
}

std::string OptionValue::choiceList() const {
    std::string list;
    for (const char* c : choices) list += (list.empty() ? "" : ", ") + std::string(c);
    return list;
}

std::string OptionValue::accepted() const {
    switch (type) {
        case OptionType::Bool:
            return "true or false";
        case OptionType::Choice:
            return "one of " + choiceList();
        case OptionType::Int:
            return "an integer in [" + showNumber(range.lo) + ", " + showNumber(range.hi) + "]";
        case OptionType::Float:
            break;
    }
    if (range.lo == 0 && std::isinf(range.hi))
        return std::string(what) + (range.loOpen ? " > 0" : " >= 0");
    return std::string(what) + " in " + (range.loOpen ? "(" : "[") + showNumber(range.lo) + ", " +
           showNumber(range.hi) + (range.hiOpen ? ")" : "]");
}

std::string OptionValue::show(double v) const {
    switch (type) {
        case OptionType::Bool:
            return v != 0 ? "true" : "false";
        case OptionType::Choice:
            return choices[static_cast<size_t>(v)];
        default:
            return showNumber(v);
    }
}

std::string OptionValue::check(double v) const {
    if (type == OptionType::Bool)
        return v == 0 || v == 1 ? "" : "expected true or false, got " + showNumber(v);
    if (type == OptionType::Choice)
        return v >= 0 && v < static_cast<double>(choices.size()) && v == std::floor(v)
                   ? ""
                   : "expected " + accepted() + ", got the index " + showNumber(v);
    const bool integral = type != OptionType::Int || v == std::floor(v);
    if (!std::isfinite(v) || !integral || !range.contains(v))
        return "expected " + accepted() + ", got " + showNumber(v);
    if (std::fabs(v) > kMaxOptionMagnitude)
        return "expected " + accepted() + ", got " + showNumber(v) +
               "; numbers must lie within +-1e9";
    return "";
}

std::string OptionValue::parse(const std::string& text, double& out) const {
    if (type == OptionType::Choice) {
        for (size_t i = 0; i < choices.size(); ++i)
            if (text == choices[i]) return out = static_cast<double>(i), "";
        return "unknown value '" + text + "'; accepted: " + choiceList();
    }
    if (type == OptionType::Bool) {
        if (text == "true" || text == "1") return out = 1, "";
        if (text == "false" || text == "0") return out = 0, "";
        return "expected true or false, got '" + text + "'";
    }
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size())
        return "expected " + accepted() + ", got '" + text + "'";
    const std::string error = check(v);
    if (error.empty()) out = v;
    return error;
}

}  // namespace sdft
