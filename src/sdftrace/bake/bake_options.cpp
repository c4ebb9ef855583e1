#include "sdftrace/bake/bake_options.h"

#include <cmath>

#include "sdftrace/core/error.h"

namespace sdft {

namespace {

#define SDFT_MEMBER(m) SDFT_OPTION_MEMBER(MeshBakeOptions, m)

std::vector<BakeOption> makeTable() {
    using T = OptionType;
    return {
        // The grid (Jamriška 2010, §3): every bake.
        {.key = "resolution",
         .flags = "--res,--resolution",
         .meshOnly = false,
         .type = T::Int,
         .range = {8, 16384},
         .what = "an integer",
         .doc = "cells along the longest axis of the region (the others in proportion)",
         SDFT_MEMBER(sampling.resolution)},
        {.key = "dense",
         .flags = "--dense",
         .meshOnly = false,
         .type = T::Bool,
         .doc = "store every sample; false: a sparse block grid with per-block cell masks "
                "(Jamriška §3)",
         .get =
             [](const MeshBakeOptions& o) {
                 return o.sampling.kind == GridKind::Dense ? 1.0 : 0.0;
             },
         .set = [](MeshBakeOptions& o,
                   double v) { o.sampling.kind = v != 0 ? GridKind::Dense : GridKind::Sparse; },
         .falseFlag = "--sparse"},
        {.key = "block",
         .flags = "--block",
         .meshOnly = false,
         .type = T::Choice,
         .choices = {"4", "8"},
         .doc = "sparse: cells per block edge",
         .get = [](const MeshBakeOptions& o) { return o.sampling.blockSize == 8 ? 1.0 : 0.0; },
         .set = [](MeshBakeOptions& o, double v) { o.sampling.blockSize = v != 0 ? 8 : 4; }},
        {.key = "band",
         .flags = "--band",
         .meshOnly = false,
         .type = T::Float,
         .range = {2, 64},
         .what = "a half-width in voxels",
         .doc = "sparse: narrow band half-width in voxels (blocks farther from the surface are "
                "dropped)",
         SDFT_MEMBER(sampling.bandVoxels)},
        {.key = "padding",
         .flags = "--padding",
         .meshOnly = false,
         .type = T::Float,
         .range = {0, 64},
         .what = "a margin in voxels",
         .doc = "empty voxels around the region, beyond the band",
         SDFT_MEMBER(sampling.paddingVoxels)},
        // How a mesh's distances and signs are computed.
        {.key = "method",
         .flags = "--method",
         .meshOnly = true,
         .type = T::Choice,
         .choices = {"exact", "jfa", "danielsson", "edt", "rtsdf"},
         .doc = "exact (closest points: a closest point transform when dense, triangles "
                "scattered over the band when sparse), jfa (jump flooding, RTSDF §2.2), "
                "danielsson (vector distance transform, Liktor §3.2), edt (exact separable "
                "distance transform of the voxelized surface), rtsdf (ray-sampled near the "
                "surface, jump-flooded beyond; RTSDF §2.1, §2.3)",
         SDFT_MEMBER(method)},
        {.key = "sign",
         .flags = "--sign",
         .meshOnly = true,
         .type = T::Choice,
         .choices = {"winding", "parity", "flood", "beta"},
         .doc = "inside/outside: winding (generalized winding number, robust on open meshes), "
                "parity (ray-crossing parity, closed meshes); jfa, danielsson and edt also flood "
                "(flood fill from the grid's boundary) or beta (|d| - beta: RTSDF's hollow shell)",
         SDFT_MEMBER(sign)},
        {.key = "closest",
         .flags = "--closest",
         .meshOnly = true,
         .type = T::Choice,
         .choices = {"transform", "bvh"},
         .doc = "exact, dense: transform (scan-convert each face's, edge's and vertex's region "
                "once; Mauch's closest point transform) or bvh (an Embree point query per vertex)",
         SDFT_MEMBER(closest)},
        {.key = "jfa_variant",
         .flags = "--jfa-variant",
         .meshOnly = true,
         .type = T::Choice,
         .choices = {"plain", "1+jfa", "jfa+2"},
         .doc = "jfa: the pass sequence (plain N/2 ... 1; 1+jfa an extra pass of offset 1 first; "
                "jfa+2 two extra passes, offsets 2 and 1, last)",
         SDFT_MEMBER(jfaVariant)},
        {.key = "beta",
         .flags = "--beta",
         .meshOnly = true,
         .type = T::Float,
         .range = {0, 100},
         .what = "a half thickness in voxels",
         .doc = "sign beta: the shell's half thickness in voxels (RTSDF §2.2)",
         SDFT_MEMBER(betaVoxels)},
        {.key = "rays",
         .flags = "--rays",
         .meshOnly = true,
         .type = T::Int,
         .range = {1, 4096},
         .what = "an integer",
         .doc = "rtsdf: rays per vertex near the surface (x)",
         SDFT_MEMBER(rtsdf.rays)},
        {.key = "mask",
         .flags = "--mask",
         .meshOnly = true,
         .type = T::Float,
         .range = {0, 64},
         .what = "a distance in voxels",
         .doc = "rtsdf: vertices whose coarse distance is within this many voxels cast rays (d)",
         SDFT_MEMBER(rtsdf.maskVoxels)},
    };
}

#undef SDFT_MEMBER

}  // namespace

std::span<const BakeOption> bakeOptions() {
    static const std::vector<BakeOption> table = makeTable();
    return table;
}

const BakeOption* findBakeOption(const std::string& key) {
    for (const BakeOption& o : bakeOptions())
        if (key == o.key) return &o;
    return nullptr;
}

std::string BakeOption::mainFlag() const { return mainFlagOf(flags); }

namespace {

const BakeOption& optionOf(const std::string& key) {
    const BakeOption* o = findBakeOption(key);
    if (!o) throw std::logic_error("no bake option '" + key + "'");
    return *o;
}

}  // namespace

void setBakeOption(MeshBakeOptions& options, const std::string& key, double v,
                   const std::string& where) {
    const BakeOption& o = optionOf(key);
    if (o.type == OptionType::Choice) {  // a number given for a choice: its word (block = 8)
        double index = 0;
        if (std::string error = o.parse(showNumber(v), index); !error.empty())
            throw InputError(where + ": " + key + " = " + showNumber(v) + ": " + error);
        o.set(options, index);
        return;
    }
    if (std::string error = o.check(v); !error.empty())
        throw InputError(where + ": " + key + " = " + showNumber(v) + ": " + error);
    o.set(options, v);
}

void setBakeOption(MeshBakeOptions& options, const std::string& key, const std::string& text,
                   const std::string& where) {
    const BakeOption& o = optionOf(key);
    double v = 0;
    if (std::string error = o.parse(text, v); !error.empty())
        throw InputError(where + ": " + key + " = '" + text + "': " + error);
    o.set(options, v);
}

std::string bakeOptionsMarkdown() {
    std::string md =
        "| key | flag | default | accepted | bakes | meaning |\n"
        "| --- | --- | --- | --- | --- | --- |\n";
    for (const BakeOption& o : bakeOptions()) {
        std::string flag = markdownCode(o.mainFlag());
        if (o.falseFlag) {
            flag += " / ";
            flag += markdownCode(o.falseFlag);
        }
        md += markdownRow({markdownCode(o.key), flag, markdownCode(o.defaultText()),
                           markdownCell(o.accepted()), o.meshOnly ? "meshes" : "all",
                           markdownCell(o.doc)});
    }
    return md;
}

std::string bakeOptionsKey(const MeshBakeOptions& options) {
    std::string key;
    for (const BakeOption& o : bakeOptions()) {
        const double v = o.get(options);
        if (v == o.defaultValue()) continue;
        if (!key.empty()) key += ' ';
        key += o.key;
        key += '=';
        key += o.show(v);
    }
    return key.empty() ? "defaults" : key;
}

}  // namespace sdft
