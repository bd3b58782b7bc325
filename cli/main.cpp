// specbake: command-line entry point. Parses arguments and dispatches to one registered subcommand.
#include "cli/command.h"
#include "cli/version.h"

#include <algorithm>
#include <cstdio>
#include <exception>
#include <vector>

namespace specbake::cli {
namespace {

struct Entry {
    const char* name;
    int order;
    AddCommand add;
};

std::vector<Entry>& registry() {
    static std::vector<Entry> entries;
    return entries;
}

}  // namespace

Registration::Registration(const char* name, int order, AddCommand add) {
    registry().push_back({name, order, add});
}

void print_error(const std::string& message) { std::fprintf(stderr, "specbake: error: %s\n", message.c_str()); }
void print_warning(const std::string& message) { std::fprintf(stderr, "specbake: warning: %s\n", message.c_str()); }

}  // namespace specbake::cli

int main(int argc, char** argv) {
    using namespace specbake::cli;
    CLI::App app{"specbake: bakes specular anti-aliasing data (filtered roughness, kernel and LEAN mips,\n"
                 "per-vertex curvature) and ships the runtime shader include that uses it.",
                 "specbake"};
    app.set_version_flag("--version", std::string("specbake ") + specbake::tool_version());
    app.require_subcommand(1);
    app.footer("Run 'specbake <command> --help' for the options and examples of each command.");

    auto& entries = registry();
    std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) { return a.order < b.order; });
    std::function<int()> run;
    for (const Entry& e : entries) e.add(app, run);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);
        return code == 0 ? kExitOk : kExitUsage;
    }
    if (!run) {
        print_error("no command given; see 'specbake --help'");
        return kExitUsage;
    }
    try {
        return run();
    } catch (const std::exception& e) {
        print_error(std::string("internal error: ") + e.what());
        return kExitFailed;
    }
}
