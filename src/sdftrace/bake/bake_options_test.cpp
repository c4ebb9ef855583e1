#include "sdftrace/bake/bake_options.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "docs/docs_section.h"
#include "sdftrace/core/error.h"

namespace sdft {
namespace {

// A value the option accepts that differs from its default.
double otherValue(const BakeOption& o) {
    const double d = o.defaultValue();
    switch (o.type) {
        case OptionType::Bool:
            return d != 0 ? 0 : 1;
        case OptionType::Choice:
            return std::fmod(d + 1, static_cast<double>(o.choices.size()));
        case OptionType::Int:
            return d != o.range.lo ? o.range.lo : o.range.lo + 1;
        case OptionType::Float:
            return d != o.range.hi ? o.range.hi : o.range.lo;
    }
    return d;
}

TEST(BakeOptions, DocsTableIsTheOptionTable) {
    EXPECT_EQ(test_support::docsSection("cli.md", "bake-options"), bakeOptionsMarkdown())
        << "regenerate the table with `sdftrace bake --list-options`";
}

TEST(BakeOptions, KeysFlagsAndDefaultsAreConsistent) {
    std::set<std::string> keys, flags;
    bool meshOnlySeen = false;
    for (const BakeOption& o : bakeOptions()) {
        EXPECT_TRUE(keys.insert(o.key).second) << o.key;
        std::string flag = ",--";
        flag += o.key;
        flag += ',';
        for (char& c : flag) c = c == '_' ? '-' : c;
        std::string all = ",";
        all += o.flags;
        all += ',';
        EXPECT_NE(all.find(flag), std::string::npos)
            << o.key << ": the key spelled as a flag is one of its flags";
        EXPECT_TRUE(flags.insert(o.mainFlag()).second) << o.key;
        EXPECT_NE(std::string(o.doc), "") << o.key;
        double v = 0;
        EXPECT_EQ(o.parse(o.defaultText(), v), "") << o.key << ": the default is accepted";
        EXPECT_EQ(static_cast<float>(v), static_cast<float>(o.defaultValue())) << o.key;
        if (o.type == OptionType::Choice) {
            EXPECT_GE(o.choices.size(), 2u) << o.key;
        }
        EXPECT_EQ(o.falseFlag != nullptr, o.type == OptionType::Bool) << o.key;
        // The grid's options come first: a front end that takes only those takes a prefix.
        if (!o.meshOnly) {
            EXPECT_FALSE(meshOnlySeen) << o.key;
        }
        meshOnlySeen = meshOnlySeen || o.meshOnly;
    }
    EXPECT_EQ(findBakeOption("no_such_key"), nullptr);
}

// The choices' words are the library's own names for the values they set.
TEST(BakeOptions, ChoicesAreTheLibrarysNames) {
    MeshBakeOptions o;
    for (size_t i = 0; i < findBakeOption("method")->choices.size(); ++i) {
        findBakeOption("method")->set(o, static_cast<double>(i));
        EXPECT_EQ(meshBakeMethodName(o.method), std::string(findBakeOption("method")->choices[i]));
    }
    for (size_t i = 0; i < findBakeOption("sign")->choices.size(); ++i) {
        findBakeOption("sign")->set(o, static_cast<double>(i));
        SignMethod parsed{};
        EXPECT_TRUE(parseSignMethod(findBakeOption("sign")->choices[i], parsed));
        EXPECT_EQ(parsed, o.sign) << findBakeOption("sign")->choices[i];
    }
    for (size_t i = 0; i < findBakeOption("closest")->choices.size(); ++i) {
        findBakeOption("closest")->set(o, static_cast<double>(i));
        ClosestPoints parsed{};
        EXPECT_TRUE(parseClosestPoints(findBakeOption("closest")->choices[i], parsed));
        EXPECT_EQ(parsed, o.closest) << findBakeOption("closest")->choices[i];
    }
    setBakeOption(o, "block", 8, "test");
    EXPECT_EQ(o.sampling.blockSize, 8);
    setBakeOption(o, "jfa_variant", "jfa+2", "test");
    EXPECT_EQ(o.jfaVariant, JfaVariant::JfaPlusTwo);
    setBakeOption(o, "dense", 1, "test");
    EXPECT_EQ(o.sampling.kind, GridKind::Dense);
}

// Each row reads and writes its own member and no other row's.
TEST(BakeOptions, EachOptionSetsOneMember) {
    const auto options = bakeOptions();
    for (const BakeOption& o : options) {
        MeshBakeOptions s;
        const double v = otherValue(o);
        ASSERT_EQ(o.check(v), "") << o.key;
        o.set(s, v);
        EXPECT_EQ(static_cast<float>(o.get(s)), static_cast<float>(v)) << o.key;
        for (const BakeOption& other : options) {
            if (&other != &o) {
                EXPECT_EQ(other.get(s), other.defaultValue()) << o.key << " moved " << other.key;
            }
        }
        EXPECT_NE(bakeOptionsKey(s).find(o.key), std::string::npos) << o.key;
    }
    EXPECT_EQ(bakeOptionsKey(MeshBakeOptions{}), "defaults");
}

TEST(BakeOptions, ARefusedValueNamesWhereTheKeyAndWhatIsAccepted) {
    MeshBakeOptions o;
    auto message = [&](auto&& set) {
        try {
            set();
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_EQ(message([&] { setBakeOption(o, "resolution", 4, "bake"); }),
              "bake: resolution = 4: expected an integer in [8, 16384], got 4");
    EXPECT_EQ(message([&] { setBakeOption(o, "resolution", 64.5, "bake"); }),
              "bake: resolution = 64.5: expected an integer in [8, 16384], got 64.5");
    EXPECT_EQ(message([&] { setBakeOption(o, "band", NAN, "to_grid"); }),
              "to_grid: band = nan: expected a half-width in voxels in [2, 64], got nan");
    EXPECT_EQ(message([&] { setBakeOption(o, "method", "magic", "bake"); }),
              "bake: method = 'magic': unknown value 'magic'; accepted: exact, jfa, danielsson, "
              "edt, rtsdf");
    EXPECT_EQ(message([&] { setBakeOption(o, "block", 6, "bake"); }),
              "bake: block = 6: unknown value '6'; accepted: 4, 8");
    EXPECT_EQ(o.sampling.resolution, MeshBakeOptions{}.sampling.resolution) << "left as it was";
}

}  // namespace
}  // namespace sdft
