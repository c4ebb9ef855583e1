#include <cmath>
#include <sstream>
#include <vector>

#include "commands.h"
#include "sdftrace/math/vec.h"

namespace sdft::cli {

Vec3Arg parseVec3Arg(const std::string& flag, const std::string& text) {
    std::vector<std::string> parts;
    std::stringstream in(text);
    std::string part;
    while (std::getline(in, part, ',')) parts.push_back(part);
    auto bad = [&] {
        return CLI::ValidationError(
            flag, "expected three finite numbers x,y,z (each within +-1e9), got '" + text + "'");
    };
    if (parts.size() != 3) throw bad();
    float v[3];
    for (int i = 0; i < 3; ++i) {
        try {
            size_t used = 0;
            v[i] = std::stof(parts[i], &used);
            if (used != parts[i].size() || !(std::fabs(v[i]) <= kMaxCoordinate)) throw bad();
        } catch (const std::exception&) {
            throw bad();
        }
    }
    return {v[0], v[1], v[2]};
}

}  // namespace sdft::cli
