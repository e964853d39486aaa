#pragma once
// Each subcommand of build/terrain registers itself on the CLI11 app and
// returns the function that runs it once parsing succeeded.
#include <functional>
#include <string>

#include <CLI/CLI.hpp>

namespace terrain::app {

using Runner = std::function<int()>;

Runner addSimCommand(CLI::App& app);
Runner addGiCommand(CLI::App& app);
Runner addRenderCommand(CLI::App& app);
Runner addDemoCommand(CLI::App& app);

}  // namespace terrain::app
