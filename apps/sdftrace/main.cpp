// sdftrace: build and ray trace signed distance fields.
#include <cstdio>
#include <exception>

#include "commands.h"
#include "sdftrace/core/error.h"

int main(int argc, char** argv) {
    CLI::App app{"sdftrace: build and ray trace signed distance fields"};
    app.name("sdftrace");
    app.require_subcommand(1);
    app.set_version_flag("--version", "sdftrace 0.1.0");
    sdft::cli::Action action;
    sdft::cli::addRenderCommand(app, action);
    sdft::cli::addBakeCommand(app, action);
    sdft::cli::addInfoCommand(app, action);
    sdft::cli::addConvertCommand(app, action);
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        // One line: what was wrong and where to look.
        const CLI::App* sub = app.get_subcommands().empty() ? &app : app.get_subcommands().front();
        std::string name = sub == &app ? "sdftrace" : "sdftrace " + sub->get_name();
        std::fprintf(stderr, "%s: error: %s (see '%s --help')\n", name.c_str(), e.what(),
                     name.c_str());
        return 2;
    }
    try {
        return action ? action() : 2;
    } catch (const sdft::InputError& e) {
        std::fprintf(stderr, "sdftrace: error: %s\n", e.what());
        return 1;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "sdftrace: error: out of memory\n");
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "sdftrace: error: %s\n", e.what());
        return 1;
    }
}
