// `terrain_bench long-run`: the built-in erosion and waves scenes for many
// ticks with a GI frame every few ticks (sim + GI through the frame pipeline,
// 2x sub-sampling, one bounce), checking as it goes that
//   - every layer of the state and every lit array stays finite,
//   - conservation holds: bedrock + soil + suspended sediment of the erosion
//     scene (closed edges; rain and evaporation change only the water) stays
//     within a relative 1e-4 of its start; the waves scene's water (an open
//     swell edge and drops change it by design) stays within 5 % of its
//     start: a drift, not a balance,
//   - memory is flat: the resident set at the end is no more than 2 % (or
//     4 MiB) above what it was after the first tenth of the run.
// Writes long_run.md and long_run.csv (one row per sample); with --check it
// writes nothing and only exits 1 on the first broken condition (the test
// command runs a short version).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "bench/suites.h"
#include "core/error.h"
#include "engine/pipeline.h"
#include "sim/scene.h"

namespace terrain::bench {
namespace {

struct LongRunOptions {
    std::vector<std::string> scenes{"erosion", "waves"};
    int size = 256;
    long long ticks = 100000;
    int giEvery = 10;
    int samples = 100;  // rows per scene in the CSV
    bool check = false;
};

struct Sample {
    long long tick;
    double simTime, material, water, rssMiB;
};

struct SceneRun {
    std::string scene;
    std::vector<Sample> samples;
    double peakMiB = 0.0, warmMiB = 0.0;
    double materialDrift = 0.0, waterDrift = 0.0;
    double seconds = 0.0;
    std::string failure;  // empty: every condition held
};

// VmRSS or VmHWM of this process in MiB (0 where /proc is not there).
double procStatusMiB(const char* key) {
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind(key, 0) == 0) return std::stod(line.substr(line.find(':') + 1)) / 1024.0;
    return 0.0;
}

double sumOf(const Grid& g) {
    double s = 0.0;
    for (float v : g.v) s += v;
    return s;
}

bool finite(const std::vector<float>& v) {
    for (float x : v)
        if (!std::isfinite(x)) return false;
    return true;
}

// The first non-finite thing in the state or the lit frame, or "".
std::string nonFinite(const engine::FramePipeline& p) {
    try {
        checkFinite(p.simulation().state());
    } catch (const InputError& e) {
        return e.what();
    }
    const engine::FrameData& f = p.frame();
    if (!finite(f.shade) || !finite(f.key)) return "the lit frame holds a NaN or Inf";
    return "";
}

Sample sampleOf(const engine::FramePipeline& p) {
    const TerrainState& s = p.simulation().state();
    return {s.tick, s.time, sumOf(s.bedrock) + sumOf(s.soil) + sumOf(s.suspended), sumOf(s.water),
            procStatusMiB("VmRSS")};
}

// The broken condition at the end of a run, or "".
std::string judge(SceneRun& r, bool conservesMaterial) {
    const Sample &first = r.samples.front(), &last = r.samples.back();
    r.materialDrift = std::fabs(last.material - first.material) / std::max(1.0, std::fabs(first.material));
    r.waterDrift = first.water > 0 ? std::fabs(last.water - first.water) / first.water : 0.0;
    if (conservesMaterial && r.materialDrift > 1e-4) return "material drifted by " + std::to_string(r.materialDrift);
    if (!conservesMaterial && r.waterDrift > 0.05) return "water drifted by " + std::to_string(r.waterDrift);
    const double slack = std::max(4.0, 0.02 * r.warmMiB);
    if (last.rssMiB > r.warmMiB + slack)
        return "memory grew from " + std::to_string(r.warmMiB) + " to " + std::to_string(last.rssMiB) + " MiB";
    return "";
}

SceneRun runScene(const std::string& name, const LongRunOptions& o) {
    SceneRun r{name, {}, 0, 0, 0, 0, 0, ""};
    engine::PipelineSettings ps;
    ps.lighting = engine::LightingMode::Global;
    ps.gi.subsample = 2;
    ps.gi.indirect.bounces = 1;
    ps.ticksPerFrame = o.giEvery;
    engine::FramePipeline p(builtinScene(name, o.size, 1), ps);
    const SceneSettings& scene = p.simulation().settings();
    const long long frames = std::max<long long>(1, o.ticks / o.giEvery);
    const long long every = std::max<long long>(1, frames / o.samples);
    const auto start = std::chrono::steady_clock::now();
    p.advance();  // the scene's spin-up: the run's ticks count from its end
    p.light();
    r.samples.push_back(sampleOf(p));
    for (long long frame = 1; frame <= frames && r.failure.empty(); ++frame) {
        p.advance();
        p.light();
        r.failure = nonFinite(p);
        if (frame == std::max<long long>(1, frames / 10)) r.warmMiB = procStatusMiB("VmRSS");
        if (frame % every == 0 || frame == frames) r.samples.push_back(sampleOf(p));
        if (frame % std::max<long long>(1, frames / 10) == 0)
            std::fprintf(stderr, "long-run %s: %lld of %lld ticks\n", name.c_str(), frame * o.giEvery,
                         frames * o.giEvery);
    }
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    r.peakMiB = procStatusMiB("VmHWM");
    if (r.failure.empty()) r.failure = judge(r, scene.hydraulic && !scene.waves);
    return r;
}

std::string csvOf(const std::vector<SceneRun>& runs) {
    std::ostringstream csv;
    csv << "scene,tick,sim_time_s,material_m_cells,water_m_cells,rss_mib\n";
    for (const SceneRun& r : runs)
        for (const Sample& s : r.samples)
            csv << r.scene << ',' << s.tick << ',' << s.simTime << ',' << s.material << ',' << s.water << ','
                << s.rssMiB << '\n';
    return csv.str();
}

std::string markdownOf(const std::vector<SceneRun>& runs, const LongRunOptions& o, const BenchContext& ctx) {
    std::ostringstream md;
    md << "# Long runs: " << o.ticks << " ticks at " << o.size << "², a GI frame every " << o.giEvery << " ticks\n\n`"
       << ctx.command << "`\n\nMachine: " << machineDescription()
       << ". Frame pipeline: 2x sub-sampling, one bounce. Ticks and simulated time count from the end of the scene's "
          "spin-up; samples in long_run.csv.\n\n"
       << "| scene | ticks | simulated s | wall s | material drift | water drift | RSS after 1/10 (MiB) "
          "| RSS at end (MiB) | max RSS (MiB) | result |\n|---|---|---|---|---|---|---|---|---|---|\n";
    for (const SceneRun& r : runs) {
        const Sample &first = r.samples.front(), &last = r.samples.back();
        md << "| " << r.scene << " | " << last.tick - first.tick << " | " << last.simTime - first.simTime << " | "
           << r.seconds << " | " << r.materialDrift << " | "
           << (r.samples.front().water > 0 ? std::to_string(r.waterDrift) : "-") << " | " << r.warmMiB << " | "
           << last.rssMiB << " | " << r.peakMiB << " | " << (r.failure.empty() ? "finite, conserved, flat" : r.failure)
           << " |\n";
    }
    md << "\nMaterial drift: |change| of bedrock + soil + suspended over its start (the erosion scene must "
          "keep it within 1e-4); water drift: the same for the water (the waves scene's open swell edge "
          "and drops change it, so only a 5 % bound); memory is flat when the RSS at the end is within "
          "2 % (or 4 MiB) of the RSS after the first tenth.\n";
    return md.str();
}

}  // namespace

Runner addLongRunSuite(CLI::App& app, const BenchContext& ctx) {
    auto o = std::make_shared<LongRunOptions>();
    CLI::App* sub = app.add_subcommand("long-run",
                                       "Many ticks of erosion and waves with GI: finite, conserved, flat "
                                       "memory (long_run.md, long_run.csv)");
    sub->add_option("--scenes", o->scenes, "Built-in scenes")->delimiter(',')->capture_default_str();
    sub->add_option("--size", o->size, "Grid side")->check(CLI::Range(16, 4096))->capture_default_str();
    sub->add_option("--ticks", o->ticks, "Ticks per scene")->check(CLI::Range(1LL, 100000000LL))->capture_default_str();
    sub->add_option("--gi-every", o->giEvery, "Ticks per GI frame")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    sub->add_flag("--check", o->check, "Write nothing; exit 1 when a condition breaks");
    return [o, &ctx] {
        std::vector<SceneRun> runs;
        bool ok = true;
        for (const std::string& name : o->scenes) {
            runs.push_back(runScene(name, *o));
            if (!runs.back().failure.empty()) {
                std::fprintf(stderr, "long-run %s: %s\n", name.c_str(), runs.back().failure.c_str());
                ok = false;
            }
        }
        if (!o->check) {
            writeResult(ctx.outDir, "long_run.csv", csvOf(runs));
            writeResult(ctx.outDir, "long_run.md", markdownOf(runs, *o, ctx));
        }
        return ok ? 0 : 1;
    };
}

}  // namespace terrain::bench
