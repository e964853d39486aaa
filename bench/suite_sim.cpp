// `terrain_bench sim`: ticks/s and cell-updates/s of the erosion and waves
// scenes at 256^2, 512^2, 1024^2 with 1 and 2 threads, median of several runs.
// Two figures per case: the kernels alone (hydraulic + thermal, or waves, one
// step at the scene's dt) and the whole Simulation::tick (plus the stability
// check and change tracking). Writes sim.md and sim.csv.
#include <chrono>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "bench/suites.h"
#include "core/parallel.h"
#include "sim/scene.h"

namespace terrain::bench {
namespace {
double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

struct SimOptions {
    int runs = 7;
    int ticks = 20;
};

struct Row {
    std::string scene;
    int size, threads;
    double kernelMs, tickMs;
    double tickIqrMs = 0.0;  // the spread of tickMs over the runs
};

Row measure(const char* scene, int size, int threads, const SimOptions& o) {
    const int runs = o.runs, ticks = o.ticks;
    Row r{scene, size, threads, 0, 0, 0};
    withThreads(threads, [&] {
        SceneSettings s = builtinScene(scene, size, 1);
        Simulation sim(s);
        // warm up: let water spread so the timing is of a running scene
        for (int t = 0; t < 10; ++t) sim.tick();
        std::vector<double> kernel, tick;
        HydraulicScratch hs;
        ThermalScratch ts;
        WaveScratch ws;
        TerrainState copy = sim.state();
        for (int run = 0; run < runs; ++run) {
            double t0 = now();
            for (int t = 0; t < ticks; ++t) {
                if (s.waves) waveStep(copy, s.waveSettings, sim.dt(), ws);
                if (s.hydraulic) hydraulicStep(copy, s.hydraulicSettings, sim.dt(), hs);
                if (s.thermal) thermalStep(copy, s.thermalSettings, sim.dt(), ts);
            }
            kernel.push_back((now() - t0) / ticks);
            t0 = now();
            for (int t = 0; t < ticks; ++t) sim.tick();
            tick.push_back((now() - t0) / ticks);
        }
        r.kernelMs = 1e3 * median(kernel);
        const Spread t = spreadOf(tick);
        r.tickMs = 1e3 * t.median;
        r.tickIqrMs = 1e3 * t.iqr();
    });
    return r;
}

void writeReport(const std::vector<Row>& rows, const SimOptions& o, const BenchContext& ctx) {
    const int runs = o.runs, ticks = o.ticks;
    std::ostringstream md, csv;
    md << "# Simulation benchmark\n\n"
       << "Machine: " << machineDescription() << ".\n\n"
       << "Command: `" << ctx.command << "`. Each figure is the median of " << runs << " runs of " << ticks
       << " ticks, after 10 warm-up ticks; IQR: the interquartile range of the runs' tick time. *kernels*: the scene's "
          "simulation steps "
       << "alone (erosion: hydraulic + thermal; waves: shallow water); *tick*: `Simulation::tick` "
       << "(kernels + stability check + change tracking).\n\n"
       << "| scene | size | threads | kernels ms/tick | tick ms/tick | IQR | ticks/s | Mcell-updates/s |\n"
       << "|---|---|---|---|---|---|---|---|\n";
    csv << "scene,size,threads,kernel_ms,tick_ms,ticks_per_s,mcell_updates_per_s,tick_iqr_ms\n";
    char buf[256];
    for (const Row& r : rows) {
        const double tps = 1e3 / r.tickMs;
        const double mcells = tps * r.size * r.size * 1e-6;
        std::snprintf(buf, sizeof buf, "| %s | %d² | %d | %.2f | %.2f | %.2f | %.1f | %.1f |\n", r.scene.c_str(),
                      r.size, r.threads, r.kernelMs, r.tickMs, r.tickIqrMs, tps, mcells);
        md << buf;
        std::snprintf(buf, sizeof buf, "%s,%d,%d,%.3f,%.3f,%.2f,%.2f,%.3f\n", r.scene.c_str(), r.size, r.threads,
                      r.kernelMs, r.tickMs, tps, mcells, r.tickIqrMs);
        csv << buf;
    }
    auto find = [&](const char* scene) {
        for (const Row& r : rows)
            if (r.scene == scene && r.size == 1024 && r.threads == 2) return r;
        return Row{};
    };
    const Row e = find("erosion"), w = find("waves");
    std::snprintf(buf, sizeof buf,
                  "\nTargets at 1024², 2 threads: erosion tick <= 15 ms: kernels %.2f ms, tick %.2f ms (%s); "
                  "waves tick <= 8 ms: kernels %.2f ms, tick %.2f ms (%s).\n",
                  e.kernelMs, e.tickMs, e.tickMs <= 15.0 ? "met" : "not met", w.kernelMs, w.tickMs,
                  w.tickMs <= 8.0 ? "met" : "not met");
    md << buf;
    writeResult(ctx.outDir, "sim.md", md.str());
    writeResult(ctx.outDir, "sim.csv", csv.str());
    std::printf("%s", buf);
}

int runSim(const SimOptions& o, const BenchContext& ctx) {
    std::vector<Row> rows;
    for (const char* scene : {"erosion", "waves"})
        for (int size : {256, 512, 1024})
            for (int threads : {1, 2}) {
                const Row r = measure(scene, size, threads, o);
                std::printf("%-8s %5d^2 %d thread(s): kernels %8.2f ms  tick %8.2f ms  (%.1f Mcell/s)\n", scene, size,
                            threads, r.kernelMs, r.tickMs, 1e-3 * size * size / r.tickMs);
                std::fflush(stdout);
                rows.push_back(r);
            }
    writeReport(rows, o, ctx);
    return 0;
}

}  // namespace

Runner addSimSuite(CLI::App& app, const BenchContext& ctx) {
    auto o = std::make_shared<SimOptions>();
    CLI::App* sub = app.add_subcommand("sim", "Simulation speed: erosion and waves at 256^2..1024^2, 1 and 2 threads");
    addRunsOption(*sub, o->runs, "Runs per figure (the median is reported)");
    sub->add_option("--ticks", o->ticks, "Ticks per run")->check(CLI::PositiveNumber)->capture_default_str();
    return [o, &ctx] { return runSim(*o, ctx); };
}

}  // namespace terrain::bench
