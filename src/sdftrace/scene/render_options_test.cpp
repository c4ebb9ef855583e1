#include "sdftrace/scene/render_options.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "docs/docs_section.h"
#include "sdftrace/core/error.h"
#include "sdftrace/scene/parse_scene.h"

namespace sdft {
namespace {

// A value the option accepts that differs from its default.
double otherValue(const RenderOption& o) {
    const double d = o.get(RenderSettings{});
    switch (o.type) {
        case OptionType::Bool:
            return d != 0 ? 0 : 1;
        case OptionType::Choice:
            return std::fmod(d + 1, static_cast<double>(o.choices.size()));
        case OptionType::Int:
            return d != o.range.lo ? o.range.lo : o.range.lo + 1;
        case OptionType::Float: {
            const double v = d * 0.5 + (o.range.loOpen ? 0.0 : o.range.lo * 0.5);
            return v != d && o.range.contains(v) ? v : (d == 0 ? 0.25 : d * 0.75);
        }
    }
    return d;
}

std::string jsonValue(const RenderOption& o, double v) {
    const std::string shown = o.show(v);
    return o.type == OptionType::Choice ? "\"" + shown + "\"" : shown;
}

std::string sceneWith(const std::string& render) {
    return R"({"render": {)" + render + R"(}, "objects": [{"type": "sphere", "radius": 1}]})";
}

TEST(RenderOptions, DocsTableIsTheOptionTable) {
    EXPECT_EQ(test_support::docsSection("cli.md", "render-options"), renderOptionsMarkdown())
        << "regenerate the table with `sdftrace render --list-options`";
}

TEST(RenderOptions, KeysFlagsAndDefaultsAreConsistent) {
    std::set<std::string> keys, flags;
    for (const RenderOption& o : renderOptions()) {
        EXPECT_TRUE(keys.insert(o.key).second) << o.key;
        std::string flag = std::string("--") + o.key;
        for (char& c : flag) c = c == '_' ? '-' : c;
        EXPECT_EQ(o.mainFlag(), flag) << "the main flag is the key spelled as a flag";
        EXPECT_TRUE(flags.insert(o.mainFlag()).second) << o.key;
        EXPECT_NE(std::string(o.doc), "") << o.key;
        double v = 0;
        EXPECT_EQ(o.parse(o.defaultText(), v), "") << o.key << ": the default is accepted";
        EXPECT_EQ(static_cast<float>(v), static_cast<float>(o.get(RenderSettings{}))) << o.key;
        if (o.type == OptionType::Choice) {
            EXPECT_GE(o.choices.size(), 2u) << o.key;
        }
    }
    EXPECT_EQ(findRenderOption("omega")->key, std::string("omega"));
    EXPECT_EQ(findRenderOption("no_such_key"), nullptr);
}

// Each row reads and writes its own member and no other row's.
TEST(RenderOptions, EachOptionSetsOneSetting) {
    const auto options = renderOptions();
    for (const RenderOption& o : options) {
        RenderSettings s;
        const double v = otherValue(o);
        ASSERT_NE(v, o.get(s)) << o.key;
        o.set(s, v);
        EXPECT_EQ(o.get(s), static_cast<double>(static_cast<float>(v))) << o.key;
        for (const RenderOption& other : options) {
            if (&other == &o) continue;
            EXPECT_EQ(other.get(s), other.get(RenderSettings{})) << o.key << " -> " << other.key;
        }
    }
}

// The scene file and the flag parser accept the same values and set the same member.
TEST(RenderOptions, SceneFileAndFlagsAgree) {
    for (const RenderOption& o : renderOptions()) {
        const double v = otherValue(o);
        Scene scene = parseSceneText(
            sceneWith(std::string("\"") + o.key + "\": " + jsonValue(o, v)), "t.json");
        RenderSettings fromFlag;
        double parsed = 0;
        ASSERT_EQ(o.parse(o.show(v), parsed), "") << o.key;
        o.set(fromFlag, parsed);
        EXPECT_EQ(o.get(scene.settings), o.get(fromFlag)) << o.key;
        EXPECT_NE(o.get(scene.settings), o.get(RenderSettings{})) << o.key;
    }
}

TEST(RenderOptions, OutOfRangeIsRejectedByBoth) {
    for (const RenderOption& o : renderOptions()) {
        if (o.type == OptionType::Bool) continue;
        double bad = o.type == OptionType::Choice ? -1 : o.range.lo - 1;
        std::string text = o.type == OptionType::Choice ? "\"nonsense\"" : std::to_string(bad);
        try {
            parseSceneText(sceneWith(std::string("\"") + o.key + "\": " + text), "t.json");
            ADD_FAILURE() << o.key << " accepted " << text;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("/render/" + std::string(o.key)),
                      std::string::npos)
                << e.what();
        }
        double out = 0;
        const std::string flagText =
            o.type == OptionType::Choice ? "nonsense" : std::to_string(bad);
        EXPECT_NE(o.parse(flagText, out), "") << o.key;
        if (o.type == OptionType::Int) {
            EXPECT_NE(o.parse("1.5", out), "") << o.key;
        }
    }
}

TEST(RenderOptions, UnknownKeyListsTheTable) {
    try {
        parseSceneText(sceneWith(R"("omgea": 1.1)"), "t.json");
        FAIL();
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("/render/omgea"), std::string::npos) << m;
        EXPECT_NE(m.find("omega"), std::string::npos) << m;
    }
}

}  // namespace
}  // namespace sdft
