// The modules' strict order (docs/design.md): core, math, exec -> field -> trace -> render ->
// scene -> view (the viewer's session), with bake beside trace (it uses field) and io beside scene
// (it reads and writes plain data of field, render and bake types; only scene, the apps and tests
// include it). Every #include "sdftrace/<module>/..." in the library's headers and sources must
// point down this order; tests and test helpers may include anything.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace sdft::e2e {
namespace {

namespace fs = std::filesystem;

// What each module may include besides itself.
const std::map<std::string, std::set<std::string>>& allowedIncludes() {
    static const std::map<std::string, std::set<std::string>> rules = {
        {"core", {}},
        {"math", {"core"}},
        {"exec", {"core"}},
        {"field", {"core", "math", "exec"}},
        {"trace", {"core", "math", "exec", "field"}},
        {"render", {"core", "math", "exec", "field", "trace"}},
        {"bake", {"core", "math", "exec", "field"}},
        {"io", {"core", "math", "exec", "field", "render", "bake"}},
        {"scene", {"core", "math", "exec", "field", "trace", "render", "bake", "io"}},
        {"gpu", {"core", "math", "exec", "field", "trace", "render", "bake"}},
        // Exact queries of meshes at points: the bakers' BVHs and winding numbers, point files.
        {"query", {"core", "math", "exec", "field", "bake", "io"}},
        {"view", {"core", "math", "exec", "field", "trace", "render", "bake", "io", "scene"}},
        // Renders and bakes across the ranks of an MPI job.
        {"cluster", {"core", "math", "exec", "field", "trace", "render", "bake", "io", "scene"}},
    };
    return rules;
}

// "<file>: includes <module>/..." for each include of `text` (a file of `module`) against the
// order.
std::vector<std::string> violations(const std::string& module, const std::string& file,
                                    const std::string& text) {
    // Public headers ("sdftrace/<module>/...") and private ones reached by a relative path
    // ("../<module>/...").
    static const std::regex include(R"(#include\s+"(?:sdftrace|\.\.)/([a-z_]+)/)");
    std::vector<std::string> out;
    const auto& allowed = allowedIncludes().at(module);
    for (std::sregex_iterator it(text.begin(), text.end(), include), end; it != end; ++it) {
        const std::string target = (*it)[1];
        if (target != module && !allowed.count(target))
            out.push_back(file + ": " + module + " includes " + target + "/");
    }
    return out;
}

bool isTestFile(const fs::path& p) {
    const std::string name = p.filename().string();
    return name.find("_test.") != std::string::npos || name.find("test_") == 0 ||
           name.find("_test_") != std::string::npos;
}

std::string readFile(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(ModuleOrder, CheckerFindsAnIncludeAgainstTheOrder) {
    EXPECT_EQ(violations("trace", "x.h", "#include \"sdftrace/render/camera.h\"\n").size(), 1u);
    EXPECT_EQ(violations("render", "x.h", "#include \"sdftrace/scene/scene.h\"\n").size(), 1u);
    EXPECT_EQ(violations("bake", "x.h", "#include \"sdftrace/io/mesh_io.h\"\n").size(), 1u);
    EXPECT_EQ(violations("bake", "x.cpp", "#include \"../io/vdb_reader.h\"\n").size(), 1u);
    EXPECT_TRUE(violations("bake", "x.cpp", "#include \"../field/openvdb_plugin.h\"\n").empty());
    EXPECT_TRUE(violations("scene", "x.h", "#include \"sdftrace/render/film.h\"\n").empty());
    EXPECT_TRUE(violations("field", "x.h", "#include \"sdftrace/field/grid.h\"\n").empty());
}

TEST(ModuleOrder, NoLibraryIncludeGoesAgainstTheOrder) {
    const fs::path root(SDFT_SOURCE_DIR);
    std::vector<std::string> found;
    size_t files = 0;
    for (const fs::path& base : {root / "include" / "sdftrace", root / "src" / "sdftrace"}) {
        for (const auto& dir : fs::directory_iterator(base)) {
            if (!dir.is_directory()) continue;
            const std::string module = dir.path().filename().string();
            ASSERT_TRUE(allowedIncludes().count(module))
                << "new module '" << module << "': give it a place in the order";
            for (const auto& f : fs::recursive_directory_iterator(dir.path())) {
                if (!f.is_regular_file() || isTestFile(f.path())) continue;
                ++files;
                for (std::string v :
                     violations(module, fs::relative(f.path(), root).string(), readFile(f.path())))
                    found.push_back(v);
            }
        }
    }
    EXPECT_GT(files, 100u) << "the walk found too few files: is SDFT_SOURCE_DIR right?";
    std::string report;
    for (const std::string& v : found) report += "\n  " + v;
    EXPECT_TRUE(found.empty()) << found.size() << " includes against the module order:" << report;
}

// The CLI uses the public API (include/) and no other internal header than these (the device
// choice is the library's, gpu/device.h; docs/decisions/0015).
TEST(ModuleOrder, AppsIncludeOnlyThePublicApi) {
    const fs::path root(SDFT_SOURCE_DIR);
    const fs::path apps = root / "apps" / "sdftrace";
    const std::set<std::string> internals = {"sdftrace/exec/thread_arena.h",
                                             "sdftrace/view/view_script.h",
                                             "sdftrace/view/viewer_session.h"};
    static const std::regex local(R"re(#include\s+"([^"]+)")re");
    size_t publicIncludes = 0;
    for (const auto& f : fs::recursive_directory_iterator(apps)) {
        if (!f.is_regular_file()) continue;
        const std::string text = readFile(f.path());
        for (std::sregex_iterator it(text.begin(), text.end(), local), end; it != end; ++it) {
            const std::string header = (*it)[1];
            if (header.rfind("sdftrace/", 0) == 0) {
                const bool isPublic = fs::exists(root / "include" / header);
                publicIncludes += isPublic;
                EXPECT_TRUE(isPublic || internals.count(header))
                    << f.path().filename() << " includes the internal " << header;
                continue;
            }
            EXPECT_TRUE(fs::exists(apps / header) || fs::exists(f.path().parent_path() / header))
                << f.path().filename() << " includes " << header;
        }
    }
    EXPECT_GT(publicIncludes, 20u) << "the walk found too few includes";
}

// The public headers include nothing from src/: an installed tree is complete.
TEST(ModuleOrder, PublicHeadersIncludeOnlyPublicHeaders) {
    const fs::path include = fs::path(SDFT_SOURCE_DIR) / "include";
    static const std::regex local(R"re(#include\s+"([^"]+)")re");
    size_t headers = 0;
    for (const auto& f : fs::recursive_directory_iterator(include)) {
        if (!f.is_regular_file()) continue;
        ++headers;
        const std::string text = readFile(f.path());
        for (std::sregex_iterator it(text.begin(), text.end(), local), end; it != end; ++it) {
            const std::string header = (*it)[1];
            EXPECT_TRUE(fs::exists(include / header))
                << fs::relative(f.path(), include) << " includes " << header
                << ", which is not a public header";
        }
    }
    EXPECT_GT(headers, 50u);
}

}  // namespace
}  // namespace sdft::e2e
