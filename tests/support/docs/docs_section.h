// What a page of docs/ holds between `<!-- name:begin -->` and `<!-- name:end -->`: the parts the
// tests hold to the code that generates them (the option tables of docs/cli.md).
#pragma once

#include <fstream>
#include <sstream>
#include <string>

namespace sdft::test_support {

// The text between the markers, or "<missing: ...>" when the page or a marker is missing (a
// comparison with it then fails and says so).
inline std::string docsSection(const std::string& page, const std::string& name) {
    std::ifstream in(std::string(SDFT_SOURCE_DIR) + "/docs/" + page);
    if (!in) return "<missing: docs/" + page + ">";
    std::stringstream text;
    text << in.rdbuf();
    const std::string doc = text.str();
    const std::string begin = "<!-- " + name + ":begin -->\n", end = "<!-- " + name + ":end -->";
    const size_t a = doc.find(begin), b = doc.find(end);
    if (a == std::string::npos || b == std::string::npos || b < a)
        return "<missing: the " + name + " markers in docs/" + page + ">";
    return doc.substr(a + begin.size(), b - a - begin.size());
}

}  // namespace sdft::test_support
