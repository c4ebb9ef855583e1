// The bake options, written once: each MeshBakeOptions member a user can set is one row (scene-file
// key and Python keyword, `sdftrace bake` flags, type, accepted range or names, default, one-line
// doc), as the render options are (scene/render_options.h). `sdftrace bake`'s flags, a scene
// file's mesh objects and "bake" nodes, sdftrace.bake() and Field.to_grid() in Python, and the
// table in docs/cli.md all come from it, so a bake option has one default, one range and one
// description wherever it is given.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/core/option_value.h"

namespace sdft {

struct BakeOption {
    const char* key;    // scene file and Python: "resolution"
    const char* flags;  // `sdftrace bake`: "--res,--resolution" (first: main)
    // false: every bake (a mesh, a scene file's field, a "bake" node, Field.to_grid); true: meshes.
    bool meshOnly;
    OptionType type;
    OptionRange range{0, 0};                // Int, Float
    const char* what = "a number";          // Int, Float (error messages)
    std::vector<const char*> choices = {};  // Choice: the accepted words, in value order
    const char* doc;                        // one line (help, docstrings, docs/cli.md)
    // The member as a number: bools 0/1, choices their index, ints and floats themselves.
    double (*get)(const MeshBakeOptions&);
    void (*set)(MeshBakeOptions&, double);
    // Bool only: the flag that sets false ("--sparse" for "--dense").
    const char* falseFlag = nullptr;

    OptionValue value() const { return {type, range, what, choices}; }
    std::string mainFlag() const;  // "--res"
    std::string accepted() const { return value().accepted(); }
    std::string show(double v) const { return value().show(v); }
    double defaultValue() const { return get(MeshBakeOptions{}); }
    std::string defaultText() const { return show(defaultValue()); }
    std::string parse(const std::string& text, double& out) const {
        return value().parse(text, out);
    }
    std::string check(double v) const { return value().check(v); }
};

// Every option, in the order docs and help list them (the options of every bake first).
std::span<const BakeOption> bakeOptions();
const BakeOption* findBakeOption(const std::string& key);

// Sets `key` to `v` after its check; throws InputError "<where>: <key> = <v>: expected ..." when
// the table refuses it (where: "bake", "to_grid").
void setBakeOption(MeshBakeOptions& o, const std::string& key, double v, const std::string& where);
// Likewise from text (a choice's word, a number as written).
void setBakeOption(MeshBakeOptions& o, const std::string& key, const std::string& text,
                   const std::string& where);

// The options as a Markdown table (key, flag, default, accepted, applies to, meaning): what
// docs/cli.md holds between its `<!-- bake-options -->` markers (a test compares them).
std::string bakeOptionsMarkdown();

// One line of the options that differ from the defaults, "method=jfa res=256": the key of a
// bake's cache entry and of its log line.
std::string bakeOptionsKey(const MeshBakeOptions& o);

}  // namespace sdft
