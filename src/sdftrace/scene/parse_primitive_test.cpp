#include <gtest/gtest.h>

#include <string>

#include "sdftrace/core/error.h"
#include "sdftrace/field/primitive_table.h"
#include "sdftrace/scene/parse_scene.h"

namespace sdft {
namespace {

// Every row of the primitive table is a scene-file type: without its parameters it asks for them
// instead of calling the type unknown.
TEST(ParsePrimitive, EveryTableRowIsASceneType) {
    const char* names[] = {
#define SDFT_PRIMITIVE_NAME(Kind, name, ...) name,
        SDFT_PRIMITIVES(SDFT_PRIMITIVE_NAME)
#undef SDFT_PRIMITIVE_NAME
    };
    for (const char* name : names) {
        const std::string text = std::string(R"({"objects": [{"type": ")") + name + R"("}]})";
        try {
            parseSceneText(text, "t.json");
            ADD_FAILURE() << name << " parsed without parameters";
        } catch (const InputError& e) {
            const std::string m = e.what();
            EXPECT_NE(m.find("missing required key"), std::string::npos) << name << ": " << m;
        }
    }
}

TEST(ParsePrimitive, UnknownTypeListsEveryPrimitive) {
    try {
        parseSceneText(R"({"objects": [{"type": "spheer"}]})", "t.json");
        FAIL();
    } catch (const InputError& e) {
        const std::string m = e.what();
#define SDFT_PRIMITIVE_LISTED(Kind, name, ...) EXPECT_NE(m.find(name), std::string::npos) << m;
        SDFT_PRIMITIVES(SDFT_PRIMITIVE_LISTED)
#undef SDFT_PRIMITIVE_LISTED
        EXPECT_NE(m.find("bake"), std::string::npos) << m;
    }
}

}  // namespace
}  // namespace sdft
