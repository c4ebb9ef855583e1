// Subcommands of the sdftrace CLI. Each registers itself on the app and sets the action to run
// when it is chosen; the action returns the process exit status.
#pragma once

#include <CLI/CLI.hpp>
#include <chrono>
#include <functional>

namespace sdft::cli {

using Action = std::function<int()>;

// Seconds since t0, for the summary lines' phase times.
inline double since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void addRenderCommand(CLI::App& app, Action& action);
void addBakeCommand(CLI::App& app, Action& action);
void addInfoCommand(CLI::App& app, Action& action);
void addConvertCommand(CLI::App& app, Action& action);
void addMeshCommand(CLI::App& app, Action& action);
void addViewCommand(CLI::App& app, Action& action);
void addQueryCommand(CLI::App& app, Action& action);

// Parses "x,y,z" (flag values); throws CLI::ValidationError naming the flag.
struct Vec3Arg {
    float x = 0, y = 0, z = 0;
};
Vec3Arg parseVec3Arg(const std::string& flag, const std::string& text);

}  // namespace sdft::cli
