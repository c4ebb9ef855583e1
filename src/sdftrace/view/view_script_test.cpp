#include "sdftrace/view/view_script.h"

#include <gtest/gtest.h>

#include "sdftrace/core/error.h"

namespace sdft {
namespace {

TEST(ViewScript, ParsesCommandsNumbersAndComments) {
    const auto cmds = parseViewScript(
        "# a test\norbit 40 -10\n\n  zoom 2   # closer\nset shadow_method soft\nset omega 1.5\n"
        "aov steps\nwait\nscreenshot out.png\nquit\n",
        "s.txt");
    ASSERT_EQ(cmds.size(), 8u);
    EXPECT_EQ(cmds[0].name, "orbit");
    EXPECT_EQ(cmds[0].numbers, (std::vector<double>{40, -10}));
    EXPECT_EQ(cmds[1].line, 4);
    EXPECT_EQ(cmds[2].numbers.at(0), 1.0);  // soft is the choice at index 1
    EXPECT_EQ(cmds[3].numbers.at(0), 1.5);
    EXPECT_EQ(cmds[6].args.at(0), "out.png");
}

void expectError(const std::string& text, const std::string& part) {
    try {
        parseViewScript(text, "s.txt");
        ADD_FAILURE() << "no error for: " << text;
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
}

TEST(ViewScript, BadLinesAreOneErrorNamingTheLineAndWhatIsAccepted) {
    expectError("orbit 1 2\nspin 3\n", "s.txt:2: unknown command 'spin'; accepted: orbit, pan");
    expectError("orbit 1\n", "s.txt:1: orbit: expected 2 arguments: orbit DX DY");
    expectError("zoom lots\n", "zoom: 'lots' is not a number");
    expectError("zoom nan\n", "is not a number");
    expectError("set omgea 1.5\n", "set: unknown render option 'omgea'");
    expectError("set omega 7\n", "set omega 7: expected an over-relaxation factor");
    expectError("set shadow_method fuzzy\n", "accepted: hard, soft");
    expectError("aov colour\n", "aov: 'colour'");
    expectError("aov motion\n", "aov: 'motion'");
    expectError("tracer fast\n", "expected classic or enhanced");
    expectError("frames 0\n", "frames: expected an integer in [1, 100000]");
    expectError("frames 2.5\n", "frames: expected an integer");
}

}  // namespace
}  // namespace sdft
