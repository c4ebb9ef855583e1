// sdftrace: build and ray trace signed distance fields.
#include <csignal>
#include <cstdio>
#include <exception>
#include <string>

#include "commands.h"
#include "sdftrace/cluster/communicator.h"
#include "sdftrace/cluster/work_farm.h"
#include "sdftrace/core/build_info.h"
#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/exec/simd.h"
#include "sdftrace/io/atomic_file.h"

namespace {
// Ctrl-C, kill, a closed terminal: no temporary output file is left behind (atomic_file.h).
void onTerminatingSignal(int sig) {
    sdft::removeTemporaryOutputs();
    std::signal(sig, SIG_DFL);
    std::raise(sig);
}

// --version: the version, the git revision and what this build includes (core/build_info.h).
std::string versionText() {
    std::string text = sdft::describeBuild(sdft::simdLevelName(sdft::simdLevel()));
    if (!text.empty() && text.back() == '\n') text.pop_back();
    return text;
}
}  // namespace

int run(int argc, char** argv);

int main(int argc, char** argv) {
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) std::signal(sig, onTerminatingSignal);
    // Under mpirun: MPI's world (docs/cluster.md); otherwise nothing changes.
    sdft::Communicator::init(argc, argv);
    const int status = run(argc, argv);
    sdft::Communicator::finalize();
    return status;
}

int run(int argc, char** argv) {
    CLI::App app{"sdftrace: build and ray trace signed distance fields"};
    app.name("sdftrace");
    app.require_subcommand(1);
    app.set_version_flag("--version", versionText);
    app.fallthrough();  // --max-memory may follow the subcommand
    app.add_option_function<std::string>(
           "--max-memory",
           [](const std::string& v) {
               double bytes = 0;
               if (!sdft::parseByteSize(v, bytes))
                   throw CLI::ValidationError("--max-memory",
                                              v + ": expected a size such as 8G, 512M or a number "
                                                  "of bytes");
               sdft::setMemoryBudgetBytes(bytes);
           },
           "Memory budget for everything whose size the input sets (films, grids, bake arrays, "
           "BVHs, shadow maps), checked before it is allocated: 8G, 512M, 1.5GiB or bytes "
           "(default: half of the physical memory)")
        ->type_name("SIZE");
    sdft::cli::Action action;
    sdft::cli::addRenderCommand(app, action);
    sdft::cli::addBakeCommand(app, action);
    sdft::cli::addInfoCommand(app, action);
    sdft::cli::addConvertCommand(app, action);
    sdft::cli::addMeshCommand(app, action);
    sdft::cli::addQueryCommand(app, action);
    sdft::cli::addViewCommand(app, action);
    // Under mpirun every rank parses the same flags: rank 0 alone prints help and flag errors.
    const bool printer = sdft::Communicator::world().root();
    try {
        try {
            app.parse(argc, argv);
        } catch (const CLI::ParseError& e) {
            if (!printer) return e.get_exit_code() == 0 ? 0 : 2;
            throw;
        }
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
    sdft::Communicator& comm = sdft::Communicator::world();
    // Only render and bake are split across ranks (docs/cluster.md); the others run on rank 0.
    if (comm.distributed() && !app.got_subcommand("render") && !app.got_subcommand("bake")) {
        if (!comm.root()) return 0;
        comm.setOthersDone();
    }
    // One line on stderr; under mpirun an error that the ranks did not agree on (others may be
    // waiting for this rank) names the rank and ends the whole job.
    auto fail = [&](const std::string& message) -> int {
        if (!comm.distributed() || comm.othersDone()) {
            std::fprintf(stderr, "sdftrace: error: %s\n", message.c_str());
            return 1;
        }
        std::fprintf(stderr, "sdftrace: error: %s: %s (the job stops)\n",
                     comm.name(comm.rank()).c_str(), message.c_str());
        std::fflush(stderr);
        comm.abort(1);
    };
    try {
        return action ? action() : 2;
    } catch (const sdft::RankFailure& e) {
        // Every rank of the job stops; rank 0 says why.
        if (e.report()) std::fprintf(stderr, "sdftrace: error: %s\n", e.what());
        return 1;
    } catch (...) {
        return fail(sdft::describeException(std::current_exception()));
    }
}
