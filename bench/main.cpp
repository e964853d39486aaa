// build/terrain_bench: the engine's benchmarks, one subcommand per suite. Each
// suite writes its results files (Markdown and CSV) to bench/results.
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "bench/suites.h"

#ifndef TERRAIN_SOURCE_DIR
#define TERRAIN_SOURCE_DIR "."
#endif

int main(int argc, char** argv) {
    using namespace terrain::bench;
    CLI::App app{"terrain_bench: benchmarks of the terrain engine (simulation, global illumination, renderer)"};
    app.require_subcommand(1);
    app.fallthrough();  // subcommands inherit it: --data and --out may also follow the subcommand
    app.set_help_all_flag("--help-all", "Print help for every subcommand");
    BenchContext ctx;
    // The real DEMs live beside the repository (../shared/data), as for sim/.
    const std::filesystem::path source(TERRAIN_SOURCE_DIR);
    ctx.dataDir = (source / ".." / "shared" / "data").lexically_normal().string();
    ctx.outDir = (source / "bench" / "results").lexically_normal().string();
    app.add_option("--data", ctx.dataDir, "Folder of the real DEMs (alps-montblanc.png, mtperdu_20m.png)")
        ->envname("TERRAIN_DATA")
        ->capture_default_str();
    app.add_option("--out", ctx.outDir, "Folder the results files are written to")->capture_default_str();
    ctx.command = "build/terrain_bench";
    for (int i = 1; i < argc; ++i) ctx.command += std::string(" ") + argv[i];

    std::vector<std::pair<CLI::App*, Runner>> suites;
    auto add = [&](Runner (*f)(CLI::App&, const BenchContext&)) {
        Runner r = f(app, ctx);
        suites.emplace_back(app.get_subcommands({}).back(), std::move(r));
    };
    add(&addSimSuite);
    add(&addRenderSuite);
    add(&addGiSuite);
    add(&addGiIndirectSuite);
    add(&addGiGlossySuite);
    add(&addGiIncrementalSuite);
    add(&addGiSunSkySuite);
    add(&addGiBoundDiagnosisSuite);
    add(&addLongRunSuite);
    add(&addSvfSagaSuite);
    add(&addTable1Suite);
    add(&addSpeedVsErrorSuite);
    add(&addScalingSuite);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    try {
        for (auto& [sub, run] : suites)
            if (sub->parsed()) return run();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "terrain_bench: error: %s\n", e.what());
        return 1;
    }
    return 1;
}
