#include "sdftrace/view/view_script.h"

#include <cmath>
#include <cstdlib>
#include <sstream>

#include "sdftrace/core/error.h"
#include "sdftrace/render/film.h"
#include "sdftrace/scene/render_options.h"

namespace sdft {

namespace {

struct CommandSpec {
    const char* name;
    int args;         // exact number of arguments
    bool numeric;     // all of them numbers
    const char* use;  // for messages
};

constexpr CommandSpec kCommands[] = {
    {"orbit", 2, true, "orbit DX DY (pixels)"},
    {"pan", 2, true, "pan DX DY (pixels)"},
    {"zoom", 1, true, "zoom CLICKS"},
    {"fly", 3, true, "fly FORWARD RIGHT UP (world units)"},
    {"reset", 0, false, "reset"},
    {"set", 2, false, "set KEY VALUE (a render option, e.g. set omega 1.5)"},
    {"tracer", 1, false, "tracer classic|enhanced"},
    {"aov", 1, false, "aov NAME"},
    {"frames", 1, true, "frames N (1 to 100000)"},
    {"wait", 0, false, "wait"},
    {"screenshot", 1, false, "screenshot PATH"},
    {"grab", 1, false, "grab PATH (the whole window, panel included, as PNG)"},
    {"command", 0, false, "command"},
    {"reload", 0, false, "reload"},
    {"quit", 0, false, "quit"},
};

std::string commandList() {
    std::string s;
    for (const CommandSpec& c : kCommands) s += (s.empty() ? "" : ", ") + std::string(c.name);
    return s;
}

}  // namespace

std::vector<ViewCommand> parseViewScript(const std::string& text, const std::string& source) {
    std::vector<ViewCommand> out;
    std::istringstream lines(text);
    std::string line;
    for (int number = 1; std::getline(lines, line); ++number) {
        if (size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
        std::istringstream words(line);
        ViewCommand c;
        c.line = number;
        if (!(words >> c.name)) continue;
        for (std::string w; words >> w;) c.args.push_back(w);
        const std::string where = source + ":" + std::to_string(number) + ": ";
        const CommandSpec* spec = nullptr;
        for (const CommandSpec& s : kCommands)
            if (c.name == s.name) spec = &s;
        if (!spec)
            throw InputError(where + "unknown command '" + c.name +
                             "'; accepted: " + commandList());
        if (static_cast<int>(c.args.size()) != spec->args)
            throw InputError(where + c.name + ": expected " + std::to_string(spec->args) +
                             " argument" + (spec->args == 1 ? "" : "s") + ": " + spec->use);
        if (spec->numeric) {
            for (const std::string& a : c.args) {
                char* end = nullptr;
                const double v = std::strtod(a.c_str(), &end);
                if (end != a.c_str() + a.size() || !std::isfinite(v) || std::fabs(v) > 1e9)
                    throw InputError(where + c.name + ": '" + a +
                                     "' is not a number within +-1e9: " + spec->use);
                c.numbers.push_back(v);
            }
        }
        if (c.name == "frames" &&
            (c.numbers[0] < 1 || c.numbers[0] > 100000 || c.numbers[0] != std::floor(c.numbers[0])))
            throw InputError(where + "frames: expected an integer in [1, 100000]");
        if (c.name == "tracer" && c.args[0] != "classic" && c.args[0] != "enhanced")
            throw InputError(where + "tracer: '" + c.args[0] + "': expected classic or enhanced");
        if (c.name == "set") {
            const RenderOption* o = findRenderOption(c.args[0]);
            if (!o)
                throw InputError(where + "set: unknown render option '" + c.args[0] +
                                 "' (render --list-options lists them)");
            double v = 0;
            if (std::string e = o->parse(c.args[1], v); !e.empty())
                throw InputError(where + "set " + c.args[0] + " " + c.args[1] + ": " + e);
            c.numbers.push_back(v);
        }
        Aov aov;
        if (c.name == "aov" && (!parseAov(c.args[0], aov) || aov == Aov::Motion))
            throw InputError(where + "aov: '" + c.args[0] +
                             "': expected color, depth, normal, steps, error, trav_steps, "
                             "isect_tests, shadow or ao");
        out.push_back(std::move(c));
    }
    return out;
}

}  // namespace sdft
