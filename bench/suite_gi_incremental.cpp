// `terrain_bench gi-incremental`: GI time per frame of incremental frames
// (GiSettings::incremental) against full recomputes on the same surfaces, the
// share of receivers recomputed, and the difference of the incremental
// result from the full one: animated erosion and waves, the static Mont
// Blanc DEM, the DEM under a sun moving 1 degree per frame, and a crater
// dropped into it. Writes gi_incremental.md and .csv.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "bench/suites.h"
#include "core/parallel.h"
#include "gi/frame.h"
#include "sim/scene.h"

namespace terrain::bench {
namespace {

struct IncrementalOptions {
    int frames = 12;
    std::vector<float> tolerances = {0.0f, 0.05f};
};

// One case: a sequence of surfaces and lights, lit twice per frame.
struct CaseResult {
    std::string name;
    int size = 0;
    float tolerance = 0.0f;
    double fullMs = 0.0, incrementalMs = 0.0;  // medians over the frames after the first
    double recomputed = 0.0;                   // mean share of receivers recomputed (frames after the first)
    double rms = 0.0, maxAbs = 0.0;            // worst over the frames: relative RMS, largest |difference| / mean
};

// A frame's surface and lights; returns false when the sequence is over.
using NextFrame = std::function<bool(int frame, Grid& surface, gi::GiLighting& light)>;

double meanOf(const std::array<Grid, 3>& g) {
    double s = 0.0;
    for (const Grid& c : g)
        for (float v : c.v) s += v;
    return s / (3.0 * static_cast<double>(g[0].v.size()));
}

void compare(const std::array<Grid, 3>& inc, const std::array<Grid, 3>& full, CaseResult& r) {
    double bias = 0.0;
    r.rms = std::max(r.rms, relRmse(inc, full, bias));
    const double mean = meanOf(full);
    double worst = 0.0;
    for (std::size_t c = 0; c < 3; ++c)
        for (std::size_t i = 0; i < full[c].v.size(); ++i)
            worst = std::max(worst, std::fabs(static_cast<double>(inc[c].v[i]) - full[c].v[i]));
    r.maxAbs = std::max(r.maxAbs, mean > 0.0 ? worst / mean : worst);
}

CaseResult runCase(const std::string& name, int size, float cell, float tolerance, int frames, const NextFrame& next) {
    CaseResult r{name, size, tolerance};
    gi::GiSettings inc;
    inc.subsample = 2;
    inc.indirect.bounces = 1;
    inc.tolerance = tolerance;
    gi::GiSettings full = inc;
    full.incremental = false;
    gi::GiState incState, fullState;
    std::vector<double> incMs, fullMs;
    Grid surface;
    gi::GiLighting light;
    withThreads(2, [&] {
        for (int f = 0; f < frames && next(f, surface, light); ++f) {
            gi::runGiFrame(surface.cview(), cell, light, inc, incState);
            gi::runGiFrame(surface.cview(), cell, light, full, fullState);
            if (f == 0) continue;  // both compute everything on the first frame
            incMs.push_back(incState.timings.total);
            fullMs.push_back(fullState.timings.total);
            r.recomputed += incState.receiversRecomputed;
            compare(incState.indirect.total, fullState.indirect.total, r);
        }
    });
    r.incrementalMs = median(incMs);
    r.fullMs = median(fullMs);
    r.recomputed /= std::max<std::size_t>(1, incMs.size());
    std::printf(
        "%-28s %5d^2 tol %.3g: full %7.2f ms, incremental %7.2f ms (%5.1f %%), recomputed %5.1f %%, "
        "rms %.2e, max %.2e\n",
        name.c_str(), size, tolerance, r.fullMs, r.incrementalMs, 100.0 * r.incrementalMs / r.fullMs,
        100.0 * r.recomputed, r.rms, r.maxAbs);
    std::fflush(stdout);
    return r;
}

gi::GiLighting sunAndSky(float azimuth) {
    gi::GiLighting l;
    l.environment = gi::sunSkyLight();
    gi::KeyLight k;
    k.azimuthDeg = azimuth;
    k.elevationDeg = 30.0f;
    k.radiusDeg = 3.0f;
    l.keys.push_back(k);
    return l;
}

// An animated scene at its pacing: ground + water after every frame's ticks.
NextFrame animated(const char* scene, int size, std::shared_ptr<Simulation>& sim, int& ticksPerFrame) {
    sim = std::make_shared<Simulation>(builtinScene(scene, size, 1));
    ticksPerFrame = sim->settings().waves ? std::max(1, static_cast<int>(0.25f / sim->dt())) : 60;
    return [sim, ticksPerFrame](int f, Grid& surface, gi::GiLighting& light) {
        if (f > 0)
            for (int t = 0; t < ticksPerFrame; ++t) sim->tick();
        const TerrainState& s = sim->state();
        surface.ensureSize(s.nx, s.ny);
        for (int y = 0; y < s.ny; ++y)
            for (int x = 0; x < s.nx; ++x) surface(x, y) = s.ground(x, y) + (s.hasWater() ? s.water(x, y) : 0.0f);
        light = sunAndSky(135.0f);
        return true;
    };
}

std::vector<CaseResult> runAll(const IncrementalOptions& o, const BenchContext& ctx) {
    std::vector<CaseResult> rows;
    for (float tol : o.tolerances) {
        for (int size : {256, 512, 1024}) {
            std::shared_ptr<Simulation> sim;
            int tpf = 0;
            const NextFrame next = animated("erosion", size, sim, tpf);
            const int frames = size == 1024 ? std::max(3, o.frames / 3) : o.frames;
            rows.push_back(runCase("erosion", size, sim->state().cellSize, tol, frames, next));
        }
        {
            std::shared_ptr<Simulation> sim;
            int tpf = 0;
            const NextFrame next = animated("waves", 512, sim, tpf);
            rows.push_back(runCase("waves", 512, sim->state().cellSize, tol, o.frames, next));
        }
        float cell = 0.0f;
        const Grid dem = alpsCentreCrop(ctx.dataDir, 512, cell);
        rows.push_back(runCase("dem, static", 512, cell, tol, o.frames, [&](int, Grid& s, gi::GiLighting& l) {
            s = dem;
            l = sunAndSky(135.0f);
            return true;
        }));
        rows.push_back(
            runCase("dem, sun 1 deg per frame", 512, cell, tol, o.frames, [&](int f, Grid& s, gi::GiLighting& l) {
                s = dem;
                l = sunAndSky(135.0f + static_cast<float>(f));
                return true;
            }));
        // a 16 x 16-cell crater, 30 m deep, at the centre on the second frame (the one measured)
        rows.push_back(runCase("dem, crater event", 512, cell, tol, 2, [&](int f, Grid& s, gi::GiLighting& l) {
            s = dem;
            if (f >= 1)
                for (int y = 248; y < 264; ++y)
                    for (int x = 248; x < 264; ++x) s(x, y) -= 30.0f;
            l = sunAndSky(135.0f);
            return true;
        }));
    }
    return rows;
}

void writeReport(const std::vector<CaseResult>& rows, const IncrementalOptions& o, const BenchContext& ctx) {
    std::ostringstream md, csv;
    md << "# Incremental GI frames against full recomputes\n\n"
       << "Machine: " << machineDescription() << ".\n\nCommand: `" << ctx.command << "`.\n\n"
       << "Per case the same surfaces and lights are lit twice per frame, with incremental frames "
       << "(`GiSettings::incremental`, tolerance as given) and with full recomputes; engine settings, 2x, one "
       << "bounce, sun-and-sky plus one key light, 2 threads. Times: median GI ms per frame over the frames after "
       << "the first (" << o.frames << " frames; erosion 1024²: " << std::max(3, o.frames / 3)
       << "; the crater: 2, the crater on the second, which is the one measured). Animated scenes at their pacing "
          "(erosion 60 ticks per frame, "
       << "waves 0.25 s). Difference of the incremental total (direct + indirect) from the full one: relative RMS "
       << "and largest |difference| over the mean, the worst frame. Today only the visibility is recomputed by tile "
       << "(gi/visibility_cache.h); indirect light reruns whenever the geometry or the lighting changed.\n\n"
       << "| case | size | tolerance | full ms | incremental ms | ratio | receivers recomputed | rel. RMS | max |\n"
       << "|---|---|---|---|---|---|---|---|---|\n";
    csv << "case,size,tolerance,full_ms,incremental_ms,recomputed,rel_rms,max_rel\n";
    char buf[320];
    for (const CaseResult& r : rows) {
        std::snprintf(buf, sizeof buf, "| %s | %d² | %g | %.2f | %.2f | %.1f %% | %.1f %% | %.2e | %.2e |\n",
                      r.name.c_str(), r.size, r.tolerance, r.fullMs, r.incrementalMs,
                      100.0 * r.incrementalMs / r.fullMs, 100.0 * r.recomputed, r.rms, r.maxAbs);
        md << buf;
        std::snprintf(buf, sizeof buf, "%s,%d,%g,%.3f,%.3f,%.4f,%.3e,%.3e\n", r.name.c_str(), r.size, r.tolerance,
                      r.fullMs, r.incrementalMs, r.recomputed, r.rms, r.maxAbs);
        csv << buf;
    }
    writeResult(ctx.outDir, "gi_incremental.md", md.str());
    writeResult(ctx.outDir, "gi_incremental.csv", csv.str());
}

}  // namespace

Runner addGiIncrementalSuite(CLI::App& app, const BenchContext& ctx) {
    auto o = std::make_shared<IncrementalOptions>();
    CLI::App* sub = app.add_subcommand(
        "gi-incremental", "Incremental GI frames vs full recomputes: erosion, waves, static DEM, moving sun, crater");
    sub->add_option("--frames", o->frames, "Frames per case")->check(CLI::Range(2, 1000))->capture_default_str();
    sub->add_option("--tolerances", o->tolerances, "GI tolerances to run")->capture_default_str();
    return [o, &ctx] {
        writeReport(runAll(*o, ctx), *o, ctx);
        return 0;
    };
}

}  // namespace terrain::bench
