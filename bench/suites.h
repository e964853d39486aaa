#pragma once
// Each suite of build/terrain_bench registers itself as a subcommand on the
// CLI11 app and returns the function that runs it once parsing succeeded.
#include <functional>
#include <string>

#include <CLI/CLI.hpp>

#include "bench/bench_common.h"

namespace terrain::bench {

using Runner = std::function<int()>;

// ctx is filled while the command line is parsed and read when the runner runs.
Runner addSimSuite(CLI::App& app, const BenchContext& ctx);
Runner addRenderSuite(CLI::App& app, const BenchContext& ctx);
Runner addGiSuite(CLI::App& app, const BenchContext& ctx);
Runner addGiIndirectSuite(CLI::App& app, const BenchContext& ctx);
Runner addGiGlossySuite(CLI::App& app, const BenchContext& ctx);
Runner addGiIncrementalSuite(CLI::App& app, const BenchContext& ctx);
Runner addGiSunSkySuite(CLI::App& app, const BenchContext& ctx);
Runner addGiBoundDiagnosisSuite(CLI::App& app, const BenchContext& ctx);
Runner addLongRunSuite(CLI::App& app, const BenchContext& ctx);
Runner addSvfSagaSuite(CLI::App& app, const BenchContext& ctx);
Runner addTable1Suite(CLI::App& app, const BenchContext& ctx);
Runner addSpeedVsErrorSuite(CLI::App& app, const BenchContext& ctx);
Runner addScalingSuite(CLI::App& app, const BenchContext& ctx);

/// The --runs option every suite has: how many frames or runs a figure is taken over.
inline CLI::Option* addRunsOption(CLI::App& sub, int& runs, const std::string& help) {
    return sub.add_option("--runs", runs, help)->check(CLI::PositiveNumber)->capture_default_str();
}

}  // namespace terrain::bench
