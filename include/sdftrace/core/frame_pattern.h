// File names numbered by frame: a pattern holding exactly one printf integer field, %d or a
// zero-padded %0Nd (at most three characters between % and d), and otherwise only %% for a
// literal percent sign, e.g. frames/out_%04d.png. Output frames of `render` and mesh sequences'
// input files both use it.
#pragma once

#include <string>

namespace sdft {

// Whether `pattern` is such a pattern.
bool isFramePattern(const std::string& pattern);

// The file name of frame `frame`; `pattern` must satisfy isFramePattern.
std::string framePath(const std::string& pattern, long long frame);

}  // namespace sdft
