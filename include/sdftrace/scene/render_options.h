// The render options, written once: each RenderSettings member a user can set is one row of a
// table (scene-file key, CLI flags, type, accepted range or names, default, one-line doc). The
// scene file's "render" block, the `render` subcommand's flags and the option table in
// docs/cli.md all come from it (pbrt-v4's ParameterDictionary, Mitsuba's Properties), so a
// setting is named, range-checked and documented in one place.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "sdftrace/core/option_value.h"
#include "sdftrace/math/camera.h"
#include "sdftrace/math/ray.h"
#include "sdftrace/render/render_settings.h"

namespace sdft {

struct RenderOption {
    const char* key;    // scene file: "render": {"<key>": value}
    const char* flags;  // CLI11 names, "--max-steps" or "--cell-intersection,--cell" (first: main)
    const char* group;  // the help section: Tracer, Shading, Shadows, Whitted, Path, Grids
    OptionType type;
    OptionRange range{0, 0};        // Int, Float
    const char* what = "a number";  // Int, Float: "an over-relaxation factor" (error messages)
    std::vector<const char*> choices = {};  // Choice: the accepted words, in value order
    const char* doc;                        // one line (help and docs/cli.md)
    // The member as a number: bools 0/1, choices their index, ints and floats themselves.
    double (*get)(const RenderSettings&);
    void (*set)(RenderSettings&, double);
    // A length whose default suits scenes a unit or more across: planRender scales it down with
    // smaller scenes unless it was given (scaleLengthDefaults).
    bool scaled = false;

    // What it accepts (core/option_value.h): accepted(), choiceList(), show(), parse(), check().
    OptionValue value() const { return {type, range, what, choices}; }
    std::string mainFlag() const;  // "--max-steps"
    std::string accepted() const { return value().accepted(); }
    std::string choiceList() const { return value().choiceList(); }
    std::string show(double v) const { return value().show(v); }
    std::string defaultText() const { return show(get(RenderSettings{})); }
    std::string parse(const std::string& text, double& out) const {
        return value().parse(text, out);
    }
    std::string check(double v) const { return value().check(v); }
    // Sets the value as given by the user (a scene file, a flag, the viewer, Python): set(), and
    // the option marked in RenderSettings::given.
    void give(RenderSettings& s, double v) const;
};

// Every option, in the order docs and help list them.
std::span<const RenderOption> renderOptions();
const RenderOption* findRenderOption(const std::string& key);

// The scene's length scale for the `scaled` options' defaults: its bounds' diagonal, or where
// unbounded the camera's distance to its target, capped at 1 (defaults suit scenes a unit or more
// across); the options not given take their default times that.
float sceneLengthFactor(const Bounds3& bounds, const CameraDesc& camera);
void scaleLengthDefaults(RenderSettings& s, float factor);

// The options as a Markdown table (key, flag, default, accepted, meaning): what docs/cli.md
// holds between its `<!-- render-options -->` markers (a test compares them).
std::string renderOptionsMarkdown();

}  // namespace sdft
