#include "sdftrace/core/frame_pattern.h"

#include <cctype>
#include <cstdio>
#include <vector>

#include "sdftrace/core/macros.h"

namespace sdft {

namespace {
// The position of the single field's 'd', or npos when the pattern is not a frame pattern.
size_t fieldConversion(const std::string& pattern) {
    size_t fields = 0, conversion = std::string::npos;
    for (size_t at = pattern.find('%'); at != std::string::npos; at = pattern.find('%', at + 1)) {
        size_t i = at + 1;
        if (i < pattern.size() && pattern[i] == '%') {  // %%
            at = i;
            continue;
        }
        while (i < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[i]))) ++i;
        if (i >= pattern.size() || pattern[i] != 'd' || i - at > 4) return std::string::npos;
        ++fields;
        conversion = i;
        at = i;
    }
    return fields == 1 ? conversion : std::string::npos;
}
}  // namespace

bool isFramePattern(const std::string& pattern) {
    return fieldConversion(pattern) != std::string::npos;
}

std::string framePath(const std::string& pattern, long long frame) {
    const size_t conversion = fieldConversion(pattern);
    SDFT_CHECK(conversion != std::string::npos);
    std::string format = pattern;
    format.insert(conversion, "ll");  // %04d -> %04lld
    std::vector<char> buf(pattern.size() + 32);
    std::snprintf(buf.data(), buf.size(), format.c_str(), frame);
    return buf.data();
}

}  // namespace sdft
