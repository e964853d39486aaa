// `terrain_bench gi-incremental`: GI time per frame of incremental frames
// (GiSettings::incremental) against full recomputes on the same surfaces, the
// share of receivers whose visibility and whose indirect light were
// recomputed, and the difference of the incremental result from the full
// one: animated erosion and waves, the static Mont Blanc DEM, the DEM under a
// sun moving 1 degree per frame, a crater dropped into it, pits added one a
// frame and never filled; a sweep of local changes of growing area; and long
// animated runs at several tolerances, from which the default tolerance is
// chosen. Writes gi_incremental.md and .csv, and gi_incremental_cost.png /
// .svg (bench/plots/gi_incremental_cost.py: the sweep's cost against its
// changed area).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
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
    std::vector<float> tolerances = {0.0f, 0.02f, 0.05f, 0.1f};
    int longFrames = 300;
    std::vector<float> longTolerances = {0.005f, 0.01f, 0.02f, 0.05f, 0.1f};
    std::string only;  // run only the cases whose name contains it, print them, write no report
    bool wanted(const std::string& name) const { return only.empty() || name.find(only) != std::string::npos; }
};

// Largest difference of an incremental result from the full one over the
// frames: RMS(d) / RMS(full) and max |d| / mean(full), every texel and channel.
struct Difference {
    double rms = 0.0, maxRel = 0.0;
    void add(const std::array<Grid, 3>& inc, const std::array<Grid, 3>& full) {
        double d2 = 0.0, f2 = 0.0, sum = 0.0, worst = 0.0;
        std::size_t n = 0;
        for (std::size_t c = 0; c < 3; ++c)
            for (std::size_t i = 0; i < full[c].v.size(); ++i, ++n) {
                const double f = full[c].v[i], d = static_cast<double>(inc[c].v[i]) - f;
                d2 += d * d;
                f2 += f * f;
                sum += f;
                worst = std::max(worst, std::fabs(d));
            }
        if (n == 0 || f2 == 0.0) return;
        rms = std::max(rms, std::sqrt(d2 / f2));
        maxRel = std::max(maxRel, worst / (sum / static_cast<double>(n)));
    }
};

// Median ms of the incremental frames' stages.
struct StageMs {
    double geometry = 0.0, visibility = 0.0, keys = 0.0, shading = 0.0, indirect = 0.0;
};

struct CaseResult {
    std::string name;
    int size = 0;
    float tolerance = 0.0f;
    double fullMs = 0.0, incrementalMs = 0.0;  // medians over the frames after the first
    double visibility = 0.0, indirect = 0.0;   // mean share of receivers recomputed (frames after the first)
    Difference diff;
    StageMs stages;
    double changedArea = -1.0;  // the sweep's share of the cells changed, (0, 1]; -1 for the other cases
    // a crater or pit: the median over the frames that drop it, and over
    // those that fill it, of each frame's incremental ms over its full ms
    // (-1 for the other cases): a new change and an undone one cost apart
    double droppedRatio = -1.0, filledRatio = -1.0;
};

// Frames of a crater or pit case: twelve events after the first, the pit
// dropped on odd frames and filled on even ones.
constexpr int kEventFrames = 13;

// A frame's surface and lights; returns false when the sequence is over.
using NextFrame = std::function<bool(int frame, Grid& surface, gi::GiLighting& light)>;

gi::GiSettings engineSettings(float tolerance) {
    gi::GiSettings s;
    s.subsample = 2;
    s.indirect.bounces = 1;
    s.tolerance = tolerance;
    return s;
}

// Lights each frame twice, incrementally and in full, and keeps the numbers.
class PairedRun {
public:
    explicit PairedRun(float tolerance) : inc_(engineSettings(tolerance)), full_(inc_) { full_.incremental = false; }
    void frame(const Grid& surface, float cell, const gi::GiLighting& light) {
        gi::runGiFrame(surface.cview(), cell, light, inc_, incState_);
        gi::runGiFrame(surface.cview(), cell, light, full_, fullState_);
        if (first_) {
            first_ = false;  // both compute everything on the first frame
            return;
        }
        const gi::GiTimings& t = incState_.timings;
        incMs_.push_back(t.total);
        fullMs_.push_back(fullState_.timings.total);
        frameRatio_.push_back(t.total / std::max(1e-9, fullState_.timings.total));
        stages_[0].push_back(t.gradient + t.pyramid);
        stages_[1].push_back(t.visibility);
        stages_[2].push_back(t.keyVisibility);
        stages_[3].push_back(t.shading);
        stages_[4].push_back(t.indirect);
        visibility_ += incState_.receiversRecomputed;
        indirect_ += incState_.indirectRecomputed;
        diff_.add(incState_.indirect.total, fullState_.indirect.total);
    }
    CaseResult result(const std::string& name, int size) const {
        CaseResult r{name, size, inc_.tolerance};
        const double n = static_cast<double>(std::max<std::size_t>(1, incMs_.size()));
        r.incrementalMs = median(incMs_);
        r.fullMs = median(fullMs_);
        r.visibility = visibility_ / n;
        r.indirect = indirect_ / n;
        r.diff = diff_;
        r.stages = {median(stages_[0]), median(stages_[1]), median(stages_[2]), median(stages_[3]), median(stages_[4])};
        return r;
    }
    /// The median ratio of the measured frames of this parity (frame 1: odd).
    double medianRatioOfFrames(int parity) const {
        std::vector<double> v;
        for (std::size_t i = 0; i < frameRatio_.size(); ++i)
            if (static_cast<int>((i + 1) % 2) == parity) v.push_back(frameRatio_[i]);
        return v.empty() ? -1.0 : median(v);
    }
    double sumIncremental() const { return sum(incMs_); }
    double sumFull() const { return sum(fullMs_); }

private:
    static double sum(const std::vector<double>& v) {
        double s = 0.0;
        for (double x : v) s += x;
        return s;
    }
    gi::GiSettings inc_, full_;
    gi::GiState incState_, fullState_;
    bool first_ = true;
    std::vector<double> incMs_, fullMs_, frameRatio_;
    std::array<std::vector<double>, 5> stages_;
    double visibility_ = 0.0, indirect_ = 0.0;
    Difference diff_;
};

void printCase(const CaseResult& r) {
    std::printf(
        "%-28s %5d^2 tol %.3g: full %7.2f ms, incremental %7.2f ms (%5.1f %%), recomputed V %5.1f %% I %5.1f %%, "
        "rms %.2e, max %.2e, stages %.1f / %.1f / %.1f / %.1f / %.1f ms\n",
        r.name.c_str(), r.size, static_cast<double>(r.tolerance), r.fullMs, r.incrementalMs,
        100.0 * r.incrementalMs / r.fullMs, 100.0 * r.visibility, 100.0 * r.indirect, r.diff.rms, r.diff.maxRel,
        r.stages.geometry, r.stages.visibility, r.stages.keys, r.stages.shading, r.stages.indirect);
    if (r.droppedRatio >= 0.0)
        std::printf("%-28s frames that drop it %5.1f %%, that fill it %5.1f %% (median per-frame ratios)\n", "",
                    100.0 * r.droppedRatio, 100.0 * r.filledRatio);
    std::fflush(stdout);
}

// events: a crater or pit case (droppedRatio, filledRatio).
CaseResult runCase(const std::string& name, int size, float cell, float tolerance, int frames, const NextFrame& next,
                   bool events = false) {
    PairedRun run(tolerance);
    Grid surface;
    gi::GiLighting light;
    withThreads(2, [&] {
        for (int f = 0; f < frames && next(f, surface, light); ++f) run.frame(surface, cell, light);
    });
    CaseResult r = run.result(name, size);
    if (events) {
        r.droppedRatio = run.medianRatioOfFrames(1);
        r.filledRatio = run.medianRatioOfFrames(0);
    }
    printCase(r);
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

// The lit surface of a simulation: ground + water.
void litSurface(const Simulation& sim, Grid& surface) {
    const TerrainState& s = sim.state();
    surface.ensureSize(s.nx, s.ny);
    for (int y = 0; y < s.ny; ++y)
        for (int x = 0; x < s.nx; ++x) surface(x, y) = s.ground(x, y) + (s.hasWater() ? s.water(x, y) : 0.0f);
}

int scenePacing(const Simulation& sim) {
    return sim.settings().waves ? std::max(1, static_cast<int>(0.25f / sim.dt())) : 60;
}

// An animated scene at its pacing: ground + water after every frame's ticks.
NextFrame animated(const char* scene, int size, std::shared_ptr<Simulation>& sim) {
    sim = std::make_shared<Simulation>(builtinScene(scene, size, 1));
    const int ticksPerFrame = scenePacing(*sim);
    return [sim, ticksPerFrame](int f, Grid& surface, gi::GiLighting& light) {
        if (f > 0)
            for (int t = 0; t < ticksPerFrame; ++t) sim->tick();
        litSurface(*sim, surface);
        light = sunAndSky(135.0f);
        return true;
    };
}

// Lowers the square of side `side` cells from (x0, y0) (cut to the grid) by 30 m.
void lowerSquare(Grid& s, int x0, int y0, int side) {
    for (int y = std::max(0, y0); y < std::min(s.ny, y0 + side); ++y)
        for (int x = std::max(0, x0); x < std::min(s.nx, x0 + side); ++x) s(x, y) -= 30.0f;
}

// The DEM with a square of side `side` cells at its centre lowered by 30 m
// on odd frames: every frame after the first drops or fills the pit.
NextFrame demWithPit(const Grid& dem, int side) {
    return [&dem, side](int f, Grid& s, gi::GiLighting& l) {
        s = dem;
        if (f % 2 == 1) lowerSquare(s, (dem.nx - side) / 2, (dem.ny - side) / 2, side);
        l = sunAndSky(135.0f);
        return true;
    };
}

// The DEM with a square pit of side `side` cells lowered by 30 m at one more
// place each frame, none filled: frame f holds pits 1 .. f, at the places
// of a 4 x 4 grid 128 cells apart (from the 512² crop's corner), so every
// frame after the first brings a new change that stays (a stricter local
// change than a pit dropped and filled, whose every other frame returns to
// the anchor's heights).
NextFrame demWithPitsAdded(const Grid& dem, int side) {
    return [&dem, side](int f, Grid& s, gi::GiLighting& l) {
        s = dem;
        for (int k = 0; k < f; ++k)
            lowerSquare(s, 64 + 128 * (k % 4) - side / 2, 64 + 128 * ((k / 4) % 4) - side / 2, side);
        l = sunAndSky(135.0f);
        return true;
    };
}

std::vector<CaseResult> runCases(const IncrementalOptions& o, const Grid& dem, float cell) {
    std::vector<CaseResult> rows;
    for (float tol : o.tolerances) {
        for (int size : {256, 512, 1024}) {
            if (!o.wanted("erosion " + std::to_string(size))) continue;
            std::shared_ptr<Simulation> sim;
            const NextFrame next = animated("erosion", size, sim);
            const int frames = size == 1024 ? std::max(3, o.frames / 3) : o.frames;
            rows.push_back(runCase("erosion", size, sim->state().cellSize, tol, frames, next));
        }
        if (o.wanted("waves 512")) {
            std::shared_ptr<Simulation> sim;
            const NextFrame waves = animated("waves", 512, sim);
            rows.push_back(runCase("waves", 512, sim->state().cellSize, tol, o.frames, waves));
        }
        if (o.wanted("dem, static"))
            rows.push_back(runCase("dem, static", 512, cell, tol, o.frames, [&](int, Grid& s, gi::GiLighting& l) {
                s = dem;
                l = sunAndSky(135.0f);
                return true;
            }));
        if (o.wanted("dem, sun 1 deg per frame"))
            rows.push_back(
                runCase("dem, sun 1 deg per frame", 512, cell, tol, o.frames, [&](int f, Grid& s, gi::GiLighting& l) {
                    s = dem;
                    l = sunAndSky(135.0f + static_cast<float>(f));
                    return true;
                }));
        if (o.wanted("dem, 16x16 crater"))
            rows.push_back(runCase("dem, 16x16 crater", 512, cell, tol, kEventFrames, demWithPit(dem, 16), true));
        if (o.wanted("dem, 51² pits added"))
            rows.push_back(runCase("dem, 51² pits added", 512, cell, tol, kEventFrames, demWithPitsAdded(dem, 51)));
    }
    return rows;
}

// Local changes of growing area on the DEM: squares lowered by 30 m; the
// points of gi_incremental_cost.png, each with its changed area.
std::vector<CaseResult> runSweep(const IncrementalOptions& o, const Grid& dem, float cell) {
    std::vector<CaseResult> rows;
    for (float tol : o.tolerances)
        for (int side : {5, 16, 51, 102, 229, 512}) {
            if (!o.wanted("dem, " + std::to_string(side) + "² pit")) continue;
            rows.push_back(runCase("dem, " + std::to_string(side) + "² pit", 512, cell, tol, kEventFrames,
                                   demWithPit(dem, side), true));
            rows.back().changedArea = static_cast<double>(side) * side / (512.0 * 512.0);
        }
    return rows;
}

// A long animated run at several tolerances: one simulation, one full state
// and one incremental state per tolerance.
struct LongRun {
    std::string scene;
    int size = 0, frames = 0;
    std::vector<CaseResult> rows;
    std::vector<double> ratio;  // sum of incremental ms / sum of full ms, per tolerance
};

LongRun runLong(const char* scene, int size, const IncrementalOptions& o) {
    LongRun out{scene, size, o.longFrames};
    Simulation sim(builtinScene(scene, size, 1));
    const int ticksPerFrame = scenePacing(sim);
    std::vector<std::unique_ptr<PairedRun>> runs;
    for (float tol : o.longTolerances) runs.push_back(std::make_unique<PairedRun>(tol));
    Grid surface;
    const gi::GiLighting light = sunAndSky(135.0f);
    withThreads(2, [&] {
        for (int f = 0; f < o.longFrames; ++f) {
            if (f > 0)
                for (int t = 0; t < ticksPerFrame; ++t) sim.tick();
            litSurface(sim, surface);
            for (auto& run : runs) run->frame(surface, sim.state().cellSize, light);
            if ((f + 1) % 50 == 0)
                std::fprintf(stderr, "  %s %d^2: frame %d of %d\n", scene, size, f + 1, o.longFrames);
        }
    });
    for (const auto& run : runs) {
        out.rows.push_back(run->result(std::string(scene) + ", long run", size));
        out.ratio.push_back(run->sumIncremental() / std::max(1e-9, run->sumFull()));
        printCase(out.rows.back());
    }
    return out;
}

// Within 0.2 % relative RMS and 1 % of the mean at any texel in every frame.
bool withinCriterion(const Difference& d) { return d.rms <= 0.002 && d.maxRel <= 0.01; }

// The largest of the long runs' tolerances that meets the criterion in both
// long runs and in every case and sweep row run at the same tolerance (0
// when none does).
float chooseTolerance(const std::vector<LongRun>& runs, const std::vector<CaseResult>& cases,
                      const IncrementalOptions& o) {
    float best = 0.0f;
    for (std::size_t k = 0; k < o.longTolerances.size(); ++k) {
        bool ok = true;
        for (const LongRun& r : runs) ok = ok && withinCriterion(r.rows[k].diff);
        for (const CaseResult& c : cases)
            if (c.tolerance == o.longTolerances[k]) ok = ok && withinCriterion(c.diff);
        if (ok) best = std::max(best, o.longTolerances[k]);
    }
    return best;
}

// events: with the sweep's column of the frames that drop and fill the pit.
std::string caseRow(const CaseResult& r, bool events = false) {
    char buf[400];
    std::snprintf(buf, sizeof buf,
                  "| %s | %d² | %g | %.2f | %.2f | %.1f %% | %.1f %% | %.1f %% | %.2e | %.2e | %.1f / %.1f / %.1f / "
                  "%.1f / %.1f |",
                  r.name.c_str(), r.size, static_cast<double>(r.tolerance), r.fullMs, r.incrementalMs,
                  100.0 * r.incrementalMs / r.fullMs, 100.0 * r.visibility, 100.0 * r.indirect, r.diff.rms,
                  r.diff.maxRel, r.stages.geometry, r.stages.visibility, r.stages.keys, r.stages.shading,
                  r.stages.indirect);
    std::string row = buf;
    if (events) {
        std::snprintf(buf, sizeof buf, " %.1f / %.1f %% |", 100.0 * r.droppedRatio, 100.0 * r.filledRatio);
        row += buf;
    }
    return row + '\n';
}

// The cases' table header; events: with the sweep's last column.
std::string caseHeader(bool events = false) {
    std::string names =
        "| case | size | tolerance | full ms | incremental ms | ratio | V recomputed | indirect re-gathered | "
        "rel. RMS | max | incremental stages ms: geometry / V / key V / shading / indirect |";
    std::string rule = "|---|---|---|---|---|---|---|---|---|---|---|";
    if (events) {
        names += " ratio, frames that drop / fill the pit |";
        rule += "---|";
    }
    return names + '\n' + rule + '\n';
}

void writeReport(const std::vector<CaseResult>& rows, const std::vector<CaseResult>& sweep,
                 const std::vector<LongRun>& longRuns, const IncrementalOptions& o, const BenchContext& ctx) {
    std::ostringstream md, csv;
    md << "# Incremental GI frames against full recomputes\n\n"
       << "Machine: " << machineDescription() << ".\n\nCommand: `" << ctx.command << "`.\n\n"
       << "Per case the same surfaces and lights are lit twice per frame, with incremental frames "
       << "(`GiSettings::incremental`, tolerance as given) and with full recomputes; engine settings, 2x, one "
       << "bounce, sun-and-sky plus one key light, 2 threads. Times: median GI ms per frame over the frames after "
       << "the first (" << o.frames << " frames; erosion 1024²: " << std::max(3, o.frames / 3)
       << "; a crater or pit: " << kEventFrames
       << ", dropped on odd frames and filled on even ones; pits added: " << kEventFrames
       << ", one more 51² pit each frame at a new place, none filled). Animated scenes at their pacing (erosion "
       << "60 ticks per frame, waves 0.25 s). Shares recomputed: of the receivers, whose environment visibility "
       << "(V) and whose indirect light were recomputed, mean over the measured frames. Difference of the "
       << "incremental total (direct + indirect) from the full one, worst frame: RMS of the difference over RMS of "
       << "the full result, and largest |difference| over the mean, every texel and channel.\n\n"
       << caseHeader();
    csv << "case,size,tolerance,full_ms,incremental_ms,v_recomputed,indirect_recomputed,rel_rms,max_rel,"
           "changed_area,dropped_ratio,filled_ratio\n";
    // The case names hold commas: quoted. changed_area is empty outside the
    // sweep, the dropped and filled ratios outside the crater and the pits.
    const auto csvRow = [&](const CaseResult& r) {
        char buf[360];
        std::snprintf(buf, sizeof buf, "\"%s\",%d,%g,%.3f,%.3f,%.4f,%.4f,%.3e,%.3e,", r.name.c_str(), r.size,
                      static_cast<double>(r.tolerance), r.fullMs, r.incrementalMs, r.visibility, r.indirect, r.diff.rms,
                      r.diff.maxRel);
        csv << buf;
        if (r.changedArea > 0.0) {
            std::snprintf(buf, sizeof buf, "%.6g", r.changedArea);
            csv << buf;
        }
        csv << ',';
        if (r.droppedRatio >= 0.0) {
            std::snprintf(buf, sizeof buf, "%.4f,%.4f", r.droppedRatio, r.filledRatio);
            csv << buf;
        } else {
            csv << ',';
        }
        csv << '\n';
    };
    for (const CaseResult& r : rows) {
        md << caseRow(r);
        csvRow(r);
    }
    md << "\n## Cost against the changed area\n\nSquares of growing side lowered by 30 m at the centre of the 512² "
       << "DEM, dropped and filled on alternate frames.\n\n![GI cost against the changed "
          "area](gi_incremental_cost.png)\n\n"
       << "Last column: the median, over the frames that drop the pit and over those that fill it, of each "
          "frame's incremental time over its full one (a new change, and one undone, which returns to the "
          "anchor's inputs).\n\n"
       << caseHeader(true);
    for (const CaseResult& r : sweep) {
        md << caseRow(r, true);
        csvRow(r);
    }
    if (!longRuns.empty()) {
        md << "\n## Long runs: choosing the default tolerance\n\n"
           << longRuns[0].frames
           << " frames per scene at its pacing; ratio: the incremental frames' total GI time over the full frames'.\n\n"
           << "| case | size | tolerance | time ratio | V recomputed | indirect re-gathered | worst rel. RMS | worst "
              "max "
              "|\n|---|---|---|---|---|---|---|---|\n";
        for (const LongRun& run : longRuns)
            for (std::size_t k = 0; k < run.rows.size(); ++k) {
                const CaseResult& r = run.rows[k];
                char buf[320];
                std::snprintf(buf, sizeof buf, "| %s | %d² | %g | %.1f %% | %.1f %% | %.1f %% | %.2e | %.2e |\n",
                              run.scene.c_str(), run.size, static_cast<double>(r.tolerance), 100.0 * run.ratio[k],
                              100.0 * r.visibility, 100.0 * r.indirect, r.diff.rms, r.diff.maxRel);
                md << buf;
                csvRow(r);
            }
        std::vector<CaseResult> cases = rows;
        cases.insert(cases.end(), sweep.begin(), sweep.end());
        md << "\nLargest tolerance within 0.2 % relative RMS and 1 % of the mean at any texel in every frame of "
           << "both runs and of every case above run at it: " << chooseTolerance(longRuns, cases, o) << ".\n";
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
    sub->add_option("--tolerances", o->tolerances, "GI tolerances of the cases and the sweep")->capture_default_str();
    sub->add_option("--long-frames", o->longFrames, "Frames of the long erosion and waves runs (0: none)")
        ->check(CLI::Range(0, 100000))
        ->capture_default_str();
    sub->add_option("--long-tolerances", o->longTolerances, "GI tolerances of the long runs")->capture_default_str();
    sub->add_option("--only", o->only,
                    "Run only the cases whose name contains this (e.g. 'pit', 'erosion 512', 'long run'), print "
                    "them and write no report");
    return [o, &ctx] {
        float cell = 0.0f;
        const Grid dem = alpsCentreCrop(ctx.dataDir, 512, cell);
        const std::vector<CaseResult> rows = runCases(*o, dem, cell);
        const std::vector<CaseResult> sweep = runSweep(*o, dem, cell);
        std::vector<LongRun> longRuns;
        if (o->longFrames > 1)
            for (const char* scene : {"erosion", "waves"})
                if (o->wanted(std::string(scene) + ", long run")) longRuns.push_back(runLong(scene, 256, *o));
        if (!o->only.empty()) return 0;  // a filtered run writes no report
        writeReport(rows, sweep, longRuns, *o, ctx);
        drawPlot(ctx, "gi_incremental_cost");
        return 0;
    };
}

}  // namespace terrain::bench
