// `terrain_bench speed-vs-error`: GI frame time against error, to show the
// trade-offs the settings make and where the engine's defaults sit among
// them. Each sweep varies one setting from the defaults (environment
// azimuths m, k_v, o_v, sub-sampling, bounces); the paper's settings are one
// more point. Errors are measured against the exact references
// (gi/reference_gi.h, cached on disk by gi_reference_cache) on Mont Blanc at
// true scale and on an eroded frame. Writes speed_vs_error.{csv,md} and
// draws bench/plots/speed_vs_error.py.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "bench/gi_reference_cache.h"
#include "bench/indirect_frame.h"
#include "bench/pareto.h"
#include "bench/suites.h"
#include "core/parallel.h"
#include "engine/pipeline.h"
#include "gi/frame.h"

namespace terrain::bench {
namespace {
using namespace terrain::gi;
using Clock = std::chrono::steady_clock;

struct SpeedVsErrorOptions {
    int runs = 7;
    bool quick = false;  // 96^2 scenes, 200 erosion ticks, fewer values per sweep
    std::string cacheDir = defaultReferenceCacheDir();
    int directions = 2048;  // gathering directions of the references
    // the sweeps' values; with --quick, those not given on the command line are thinned
    std::vector<int> azimuths{8, 12, 16, 24, 32}, levelsPerOctave{2, 3, 4, 6}, levelOffsets{1, 2, 3, 4},
        subsamples{1, 2, 4}, bounces{1, 2, 3};
    // with --quick: each sweep option's values when it is not on the command line
    struct QuickValues {
        CLI::Option* option;
        std::vector<int>* target;
        std::vector<int> values;
    };
    std::vector<QuickValues> quickValues;
};

// One sweep: a setting varied from the defaults over the listed values.
struct Sweep {
    const char* name;  // as the CSV, the tables and the legend name it
    const std::vector<int>* values;
    void (*apply)(GiSettings&, int);
};

std::vector<Sweep> sweepsOf(const SpeedVsErrorOptions& o) {
    return {
        {"m", &o.azimuths, [](GiSettings& s, int v) { s.visibility.azimuths = v; }},
        {"k_v", &o.levelsPerOctave, [](GiSettings& s, int v) { s.pyramid.levelsPerOctave = v; }},
        {"o_v", &o.levelOffsets, [](GiSettings& s, int v) { s.pyramid.levelOffset = v; }},
        {"subsample", &o.subsamples, [](GiSettings& s, int v) { s.subsample = v; }},
        {"bounces", &o.bounces, [](GiSettings& s, int v) { s.indirect.bounces = v; }},
    };
}

// What a set of settings costs and how far off it is.
struct Measurement {
    double ms = 0.0;        // median whole-frame time, 2 threads
    double msIqr = 0.0;     // its spread: the interquartile range of the frames
    double ambient = 0.0;   // RMSE of the ambient map (a sky-view factor in [0, 1])
    double direct = 0.0;    // relative RMSE of the direct shade
    double indirect = 0.0;  // relative RMSE of the indirect light
    double total = 0.0;     // relative RMSE of direct + indirect
};

// One row of the results: a sweep's value (or the paper's point) on one scene.
struct Point {
    std::string sweep, value;
    GiSettings settings;
    Measurement m;
    bool isDefault = false, onFront = false;
};

// A terrain, its albedo and its reference.
struct Scene {
    Dem dem;
    AlbedoMap albedo;
    GiReference ref;
};

// RMSE of a against b over the interior (10 % border left out, as relRmse).
double interiorRmse(const Grid& a, const Grid& b) {
    const int bx = b.nx / 10, by = b.ny / 10;
    double se = 0.0;
    long n = 0;
    for (int y = by; y < b.ny - by; ++y)
        for (int x = bx; x < b.nx - bx; ++x) {
            const double d = static_cast<double>(a(x, y)) - b(x, y);
            se += d * d;
            ++n;
        }
    return std::sqrt(se / static_cast<double>(n));
}

Measurement errorsOf(const GiState& st, const GiReference& ref, int bounces) {
    const IndirectErrors e = indirectErrors(st, ref, bounces);
    Measurement m;
    double bias = 0.0;
    m.ambient = interiorRmse(st.shade.ambient, ref.ambient);
    m.direct = relRmse(st.shade.rgb, ref.direct, bias);
    m.indirect = e.indirect;
    m.total = e.total;
    return m;
}

// The settings as the results file prints them, from the settings themselves.
std::string settingsText(const GiSettings& g) {
    char b[512];
    std::snprintf(b, sizeof b,
                  "m %d, k_v %d, o_v %d, peak blend %.2f, %s maximum, %dx, %d bounce%s, k_u %d, o_u %d, %d indirect "
                  "azimuths, %s indirect kernel, %s ambient, key lights %s, footprint tangent planes %s",
                  g.visibility.azimuths, g.pyramid.levelsPerOctave, g.pyramid.levelOffset, g.pyramid.peakBlend,
                  g.visibility.blockingMax == BlockingMax::Samples ? "sample" : "B-spline", g.subsample,
                  g.indirect.bounces, g.indirect.bounces == 1 ? "" : "s", g.indirect.radiance.levelsPerOctave,
                  g.indirect.radiance.levelOffset,
                  g.indirect.azimuths > 0 ? g.indirect.azimuths : g.visibility.azimuths,
                  g.indirect.lambert == LambertIndirect::BlockerRadiance ? "blocker radiance" : "SH",
                  g.ambient == AmbientMethod::Horizons ? "exact horizon" : "SH product",
                  g.keyLightExactCosine ? "exact cosine" : "SH cosine", g.visibility.footprintTangent ? "on" : "off");
    return b;
}

// How the reference came about, for the results file.
std::string referenceNote(const GiReference& r) {
    char b[128];
    if (r.fromCache && r.seconds <= 0.0) return "reference read from the cache";
    std::snprintf(b, sizeof b, "reference computed in %.0f s (all threads)%s", r.seconds,
                  r.fromCache ? ", read from the cache" : "");
    return b;
}

class SpeedVsErrorSuite {
public:
    SpeedVsErrorSuite(const SpeedVsErrorOptions& o, const BenchContext& ctx) : o_(o), ctx_(ctx) {}
    int run();

private:
    const SpeedVsErrorOptions& o_;
    const BenchContext& ctx_;
    const GiLighting light_ = sunSkyAndBenchKey();
    const float albedo_ = 0.6f;
    const GiSettings defaults_ = wholeFrames(engine::defaultPipelineGi());

    GiSettings paperPoint() const;
    int maxBounces() const;
    std::vector<Measurement> measureAll(const Scene& sc, const std::vector<GiSettings>& settings) const;
    std::vector<Point> pointsOf(const Scene& sc) const;
    std::string header(const std::vector<Scene>& scenes) const;
    static std::string sceneTable(const Scene& sc, const std::vector<Point>& points);
};

// The paper's settings (paperGiSettings) with the defaults' bounces and sub-sampling.
GiSettings SpeedVsErrorSuite::paperPoint() const {
    GiSettings s = wholeFrames(paperGiSettings());
    s.subsample = defaults_.subsample;
    s.indirect.bounces = defaults_.indirect.bounces;
    return s;
}

int SpeedVsErrorSuite::maxBounces() const {
    return std::max(defaults_.indirect.bounces, *std::max_element(o_.bounces.begin(), o_.bounces.end()));
}

// Times whole frames of every settings round-robin, 2 threads: a warm-up
// round, then o_.runs rounds of one frame of each in turn, so that a busy
// spell of a shared machine spreads over all of them instead of skewing one.
// Each settings' time is its median; its errors are those of its last frame
// (whole frames: every frame is the same).
std::vector<Measurement> SpeedVsErrorSuite::measureAll(const Scene& sc, const std::vector<GiSettings>& settings) const {
    std::vector<GiState> states(settings.size());
    std::vector<std::vector<double>> ms(settings.size());
    withThreads(2, [&] {
        for (int round = 0; round <= o_.runs; ++round)
            for (std::size_t i = 0; i < settings.size(); ++i) {
                const auto t0 = Clock::now();
                runGiFrame(sc.dem.heights.cview(), sc.dem.cell, light_, settings[i], states[i], &sc.albedo);
                if (round > 0) ms[i].push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
            }
    });
    std::vector<Measurement> out;
    for (std::size_t i = 0; i < settings.size(); ++i) {
        out.push_back(errorsOf(states[i], sc.ref, settings[i].indirect.bounces));
        const Spread t = spreadOf(ms[i]);
        out.back().ms = t.median;
        out.back().msIqr = t.iqr();
    }
    return out;
}

// Every sweep's points and the paper's on one scene (the defaults, which
// every sweep passes through, measured once), the Pareto front of total error
// against time marked.
std::vector<Point> SpeedVsErrorSuite::pointsOf(const Scene& sc) const {
    std::vector<Point> points;
    for (const Sweep& sw : sweepsOf(o_))
        for (int v : *sw.values) {
            Point p{sw.name, std::to_string(v), defaults_, {}, false, false};
            sw.apply(p.settings, v);
            points.push_back(p);
        }
    points.push_back({"paper", "paper", paperPoint(), {}, false, false});
    std::vector<GiSettings> distinct;
    for (const Point& p : points)
        if (std::find(distinct.begin(), distinct.end(), p.settings) == distinct.end()) distinct.push_back(p.settings);
    const std::vector<Measurement> measured = measureAll(sc, distinct);
    std::vector<CostAndError> costs;
    for (Point& p : points) {
        p.m = measured[static_cast<std::size_t>(std::find(distinct.begin(), distinct.end(), p.settings) -
                                                distinct.begin())];
        p.isDefault = p.settings == defaults_;
        costs.push_back({p.m.ms, p.m.total});
        std::fprintf(stderr, "  %s %s=%s: %.1f ms, ambient %.4f, direct %.4f, indirect %.4f, total %.4f\n",
                     sc.dem.name.c_str(), p.sweep.c_str(), p.value.c_str(), p.m.ms, p.m.ambient, p.m.direct,
                     p.m.indirect, p.m.total);
    }
    const std::vector<bool> front = paretoFront(costs);
    for (std::size_t i = 0; i < points.size(); ++i) points[i].onFront = front[i];
    return points;
}

std::string SpeedVsErrorSuite::header(const std::vector<Scene>& scenes) const {
    std::string md = "# GI: frame time against error (terrain_bench speed-vs-error)\n\n";
    md += "Machine: " + machineDescription() + ".\n\nCommand: `" + ctx_.command +
          "` (from the repository root; the references are cached in the --cache folder).\n\n";
    md += "Defaults (the engine's frame pipeline, engine::defaultPipelineGi()): " + settingsText(defaults_) +
          ". Each sweep varies one setting from them; **paper** is paperGiSettings() with the defaults' "
          "sub-sampling and bounces: " +
          settingsText(paperPoint()) + ".\n\n";
    md += "Time: median of " + std::to_string(o_.runs) +
          " whole frames (incremental frames off) after a warm-up, 2 threads, with the interquartile range of those "
          "frames (IQR); the settings of a scene take turns, "
          "one frame each per round, so that the machine's load falls on all of them alike. Lighting: sun-and-sky "
          "environment "
          "(SH) + one key light (az 135, el 35, r 5 deg), albedo 0.6 everywhere, Lambert. Errors against the exact "
          "reference (gi/reference_gi: exact direct light with 256 azimuths, the key light as an exact cap, " +
          std::to_string(o_.directions) +
          " gathering directions per texel for each bounce), on the interior (10 % border left out): ambient = "
          "RMSE of the ambient map (normal-weighted sky-view factor); direct, indirect and total = relative RMSE "
          "over the three channels. Pareto: no other point of the scene is both as fast and as accurate (total "
          "error) and better in one.\n\n";
    for (const Scene& sc : scenes) {
        char line[256];
        std::snprintf(line, sizeof line, "- %s: %s; %s\n", sc.dem.name.c_str(), sc.dem.note.c_str(),
                      referenceNote(sc.ref).c_str());
        md += line;
    }
    return md + "\n";
}

std::string SpeedVsErrorSuite::sceneTable(const Scene& sc, const std::vector<Point>& points) {
    std::string md = "## " + sc.dem.name +
                     "\n\n| sweep | value | ms / frame | IQR | ambient RMSE | direct rel. RMSE | "
                     "indirect rel. RMSE | total rel. RMSE | |\n|---|---|---|---|---|---|---|---|---|\n";
    char line[256];
    for (const Point& p : points) {
        const std::string mark = std::string(p.isDefault ? "default" : "") + (p.isDefault && p.onFront ? ", " : "") +
                                 (p.onFront ? "Pareto" : "");
        std::snprintf(line, sizeof line, "| %s | %s | %.1f | %.1f | %.4f | %.2f %% | %.2f %% | %.2f %% | %s |\n",
                      p.sweep.c_str(), p.value.c_str(), p.m.ms, p.m.msIqr, p.m.ambient, 100 * p.m.direct,
                      100 * p.m.indirect, 100 * p.m.total, mark.c_str());
        md += line;
    }
    // the front from fast to accurate, each settings once (the defaults recur in every sweep)
    std::vector<const Point*> front;
    bool defaultsListed = false;
    for (const Point& p : points) {
        if (!p.onFront || (p.isDefault && defaultsListed)) continue;
        defaultsListed = defaultsListed || p.isDefault;
        front.push_back(&p);
    }
    std::sort(front.begin(), front.end(), [](const Point* a, const Point* b) { return a->m.ms < b->m.ms; });
    md += "\nPareto front (total rel. RMSE against ms / frame), fastest first:";
    for (const Point* p : front) {
        std::snprintf(line, sizeof line, " %s (%.1f ms, %.3f %%);",
                      p->isDefault ? "defaults" : (p->sweep + " " + p->value).c_str(), p->m.ms, 100 * p->m.total);
        md += line;
    }
    md.back() = '.';
    return md + "\n\n";
}

int SpeedVsErrorSuite::run() {
    const auto t0 = Clock::now();
    const int size = o_.quick ? 96 : 256;
    std::vector<Scene> scenes;
    for (Dem& d : std::vector<Dem>{alpsCrop(ctx_.dataDir, size), erodedScene(size, o_.quick ? 200 : 2000)}) {
        Scene sc{std::move(d), {}, {}};
        sc.albedo = uniformAlbedo(sc.dem.heights.nx, sc.dem.heights.ny, albedo_);
        sc.ref = cachedReference(o_.cacheDir, sc.dem, light_, sc.albedo, maxBounces(), o_.directions);
        scenes.push_back(std::move(sc));
    }
    std::string md = header(scenes);
    std::string csv =
        "scene,sweep,value,is_default,pareto,ms,ambient_rmse,direct_rel_rmse,indirect_rel_rmse,"
        "total_rel_rmse,ms_iqr\n";
    for (const Scene& sc : scenes) {
        std::fprintf(stderr, "timing %s, %d rounds ...\n", sc.dem.name.c_str(), o_.runs);
        const std::vector<Point> points = pointsOf(sc);
        md += sceneTable(sc, points);
        for (const Point& p : points) {
            char line[256];
            std::snprintf(line, sizeof line, "%s,%s,%s,%d,%d,%.3f,%.5f,%.5f,%.5f,%.5f,%.3f\n", sc.dem.name.c_str(),
                          p.sweep.c_str(), p.value.c_str(), p.isDefault, p.onFront, p.m.ms, p.m.ambient, p.m.direct,
                          p.m.indirect, p.m.total, p.m.msIqr);
            csv += line;
        }
    }
    writeResult(ctx_.outDir, "speed_vs_error.md", md);
    writeResult(ctx_.outDir, "speed_vs_error.csv", csv);
    drawPlot(ctx_, "speed_vs_error");
    std::fprintf(stderr, "speed-vs-error: %.0f s in all\n", std::chrono::duration<double>(Clock::now() - t0).count());
    return 0;
}

void addSweepOption(CLI::App& sub, SpeedVsErrorOptions& o, const char* name, std::vector<int>& values,
                    std::vector<int> quick, const std::string& help, CLI::Validator range) {
    CLI::Option* opt = sub.add_option(name, values, help)->check(range)->delimiter(',')->capture_default_str();
    o.quickValues.push_back({opt, &values, std::move(quick)});
}

}  // namespace

Runner addSpeedVsErrorSuite(CLI::App& app, const BenchContext& ctx) {
    auto o = std::make_shared<SpeedVsErrorOptions>();
    CLI::App* sub =
        app.add_subcommand("speed-vs-error",
                           "GI frame time against error: one setting at a time varied from the defaults, and the "
                           "paper's settings, on Mont Blanc and an eroded frame (speed_vs_error.{csv,md,png,svg})");
    addRunsOption(*sub, o->runs, "Whole frames per timing after a warm-up (the median is reported)");
    sub->add_flag("--quick", o->quick, "96^2 scenes, 200 erosion ticks, fewer values per sweep (for trying it)");
    sub->add_option("--cache", o->cacheDir, "Folder the references are kept in across runs (by a hash of their inputs)")
        ->capture_default_str();
    sub->add_option("--directions", o->directions, "Gathering directions per texel of the references")
        ->check(CLI::Range(16, 1 << 20))
        ->capture_default_str();
    addSweepOption(*sub, *o, "--azimuths", o->azimuths, {8, 16, 32}, "Environment azimuths m", CLI::Range(3, 4096));
    addSweepOption(*sub, *o, "--levels-per-octave", o->levelsPerOctave, {2, 4}, "Height pyramid levels per octave k_v",
                   CLI::Range(1, 64));
    addSweepOption(*sub, *o, "--level-offsets", o->levelOffsets, {2, 3}, "Height pyramid level offsets o_v",
                   CLI::Range(0, 32));
    addSweepOption(*sub, *o, "--subsamples", o->subsamples, {1, 2}, "Sub-sampling factors (1, 2, 4)",
                   CLI::IsMember({1, 2, 4}));
    addSweepOption(*sub, *o, "--bounces", o->bounces, {1, 2}, "Indirect bounces", CLI::Range(1, 16));
    return [o, &ctx] {
        if (o->quick)
            for (const SpeedVsErrorOptions::QuickValues& q : o->quickValues)
                if (q.option->count() == 0) *q.target = q.values;
        return SpeedVsErrorSuite(*o, ctx).run();
    };
}

}  // namespace terrain::bench
