// build/terrain: the engine's command-line tool.
#include <cstdio>
#include <exception>
#include <vector>

#include "app/commands.h"
#include "core/error.h"

int main(int argc, char** argv) {
    // Progress and status lines reach a log or a pipe as they happen, not
    // when a buffer fills (a script that watches the demo's log acts on them).
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    CLI::App app{"terrain: a dynamic terrain engine (erosion, waves, global illumination on height fields)"};
    app.require_subcommand(1);
    app.set_help_all_flag("--help-all", "Print help for every subcommand");
    std::vector<std::pair<CLI::App*, terrain::app::Runner>> commands;
    auto add = [&](terrain::app::Runner (*f)(CLI::App&)) {
        const std::size_t before = app.get_subcommands({}).size();
        terrain::app::Runner r = f(app);
        auto subs = app.get_subcommands({});
        if (subs.size() > before) commands.emplace_back(subs.back(), std::move(r));
    };
    add(&terrain::app::addSimCommand);
    add(&terrain::app::addGiCommand);
    add(&terrain::app::addRenderCommand);
    add(&terrain::app::addDemoCommand);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // --help and --help-all print the help and succeed; any other parse
        // error is one line and exit 1, like every error of ours
        if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
        std::fprintf(stderr, "terrain: error: %s\n", terrain::boundedLine(e.what()).c_str());
        return 1;
    }
    try {
        for (auto& [sub, run] : commands)
            if (sub->parsed()) return run();
    } catch (const terrain::Error& e) {
        // ours, short already; kept to one line whatever a file name holds
        std::fprintf(stderr, "terrain: error: %s\n", terrain::boundedLine(e.what(), 1000).c_str());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "terrain: error: %s\n", terrain::boundedLine(e.what()).c_str());
        return 1;
    }
    return 1;
}
