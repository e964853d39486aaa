// `terrain_bench gi`: accuracy of the GI fast path against the ground truth,
// convergence in m / k_v / o_v, and time per frame, on the real DEMs. One
// subcommand per mode; without one it runs accuracy, convergence and timing.
// Writes gi_*.md and gi_*.csv (and gi_speed_error.png / .svg, drawn by
// bench/plots/gi_speed_error.py). Ground truths take minutes: they are cached
// in a scratch folder for the run, or across runs in the --cache folder.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include "bench/spread.h"
#include "bench/suites.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/parallel.h"
#include "gi/frame.h"
#include "gi/reference.h"

namespace terrain::bench {
namespace {
using namespace terrain::gi;
using Clock = std::chrono::steady_clock;

struct GiOptions {
    int runs = 5;
    bool useMin = false;   // the minimum over the frames instead of the median
    std::string cacheDir;  // ground truths kept across runs; empty: a scratch folder for this run
    int onlyCase = -1;     // stages, cpu: only this case (-1: all)
    int threads = 2;       // stages: worker threads
    std::string dump;      // stages: "write" the outputs to the cache folder, or "compare" against them
};

struct ErrorStats {
    double rmse = 0.0, bias = 0.0, maxAbs = 0.0;
    long count = 0;
};

ErrorStats compare(const Grid& fast, const Grid& ref, int stride, int border) {
    ErrorStats e;
    double s2 = 0.0, s1 = 0.0;
    for (int y = border; y < ref.ny - border; y += stride)
        for (int x = border; x < ref.nx - border; x += stride) {
            const double d = static_cast<double>(fast(x, y)) - ref(x, y);
            s2 += d * d;
            s1 += d;
            e.maxAbs = std::max(e.maxAbs, std::abs(d));
            ++e.count;
        }
    e.rmse = std::sqrt(s2 / std::max(e.count, 1L));
    e.bias = s1 / std::max(e.count, 1L);
    return e;
}

struct Timing {
    double median = 0.0, pyramid = 0.0, visibility = 0.0, key = 0.0, shading = 0.0;
};

// CPU time the whole machine spent busy (all cores), from /proc/stat, in seconds.
double machineBusySeconds() {
    std::ifstream in("/proc/stat");
    std::string cpu;
    long long user = 0, nice = 0, sys = 0, idle = 0, iowait = 0, irq = 0, softirq = 0, steal = 0;
    in >> cpu >> user >> nice >> sys >> idle >> iowait >> irq >> softirq >> steal;
    return static_cast<double>(user + nice + sys + irq + softirq + steal) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

double processCpuSeconds() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

std::string settingsName(const GiSettings& s) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "m=%d k_v=%d o_v=%d %s %s peak=%.2f ambient=%s %dx", s.visibility.azimuths,
                  s.pyramid.levelsPerOctave, s.pyramid.levelOffset,
                  s.visibility.interp == AzimuthInterp::Linear ? "linear" : "bspline",
                  s.visibility.blockingMax == BlockingMax::Samples ? "max=samples" : "max=bspline", s.pyramid.peakBlend,
                  s.ambient == AmbientMethod::Horizons ? "horizons" : "sh", s.subsample);
    return buf;
}

GiSettings paperSettings() { return wholeFrames(paperGiSettings()); }

GiSettings engineDefaults() { return wholeFrames(GiSettings{}); }

// The direct-light settings a table compares, printed from the settings
// themselves so that the text cannot drift from what ran.
std::string directSettingsText(const GiSettings& s) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "m %d, k_v %d, o_v %d, %.0f %% max-decimated octaves in the pyramid, %s",
                  s.visibility.azimuths, s.pyramid.levelsPerOctave, s.pyramid.levelOffset, 100.0 * s.pyramid.peakBlend,
                  s.visibility.blockingMax == BlockingMax::Samples ? "sample maximum" : "Eq. 16 B-spline maximum");
    return buf;
}

std::string buildFlags() {
    return std::string("GCC ") + __VERSION__ +
           ", CMAKE_BUILD_TYPE=Release (-O3 -DNDEBUG), -ffp-contract=off -fno-fast-math, baseline x86-64 (SSE2, no "
           "-march), "
           "4-wide GCC vector extensions in gi/";
}

struct Row {
    std::string label;
    GiSettings s = wholeFrames(paperGiSettings());
    ErrorStats e;
    Timing t;
};

// "| rmse | bias | max abs | ms |": the error and time cells of a row of the Markdown tables.
std::string errorCells(const Row& r) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "| %.4f | %+.4f | %.3f | %.1f |\n", r.e.rmse, r.e.bias, r.e.maxAbs, r.t.median);
    return buf;
}

// A row's settings, errors and time as CSV fields (azimuths, levels_per_octave,
// level_offset, interp if asked, blocking_max, peak_blend, subsample, rmse, bias, max_abs, ms).
std::string settingsCsv(const Row& r, bool withInterp) {
    const char* interp = !withInterp ? "" : r.s.visibility.interp == AzimuthInterp::Linear ? "linear," : "bspline,";
    char buf[256];
    std::snprintf(buf, sizeof buf, "%d,%d,%d,%s%s,%.2f,%d,%.5f,%.5f,%.4f,%.2f\n", r.s.visibility.azimuths,
                  r.s.pyramid.levelsPerOctave, r.s.pyramid.levelOffset, interp,
                  r.s.visibility.blockingMax == BlockingMax::Samples ? "samples" : "bspline", r.s.pyramid.peakBlend,
                  r.s.subsample, r.e.rmse, r.e.bias, r.e.maxAbs, r.t.median);
    return buf;
}

// One environment light (sun and sky) and one key light.
GiLighting sunSkyAndKey() {
    GiLighting light;
    light.environment = sunSkyLight();
    KeyLight key;
    key.azimuthDeg = 135.0f;
    key.elevationDeg = 30.0f;
    key.radiusDeg = 4.0f;
    light.keys.push_back(key);
    return light;
}

// mode "write" stores the grids in file; "compare" prints the largest and the
// mean change of each against the grids stored there.
void storeOrCompare(const std::string& mode, const std::string& file, const std::vector<const Grid*>& grids) {
    if (mode == "write") {
        std::ofstream out(file, std::ios::binary);
        for (const Grid* g : grids)
            out.write(reinterpret_cast<const char*>(g->data()), static_cast<std::streamsize>(g->size() * 4));
    } else {
        std::ifstream in(file, std::ios::binary);
        double maxd[4] = {}, sumd[4] = {};
        for (int k = 0; k < 4; ++k) {
            std::vector<float> old(grids[static_cast<std::size_t>(k)]->size());
            in.read(reinterpret_cast<char*>(old.data()), static_cast<std::streamsize>(old.size() * 4));
            for (std::size_t i = 0; i < old.size(); ++i) {
                const double d = std::abs(static_cast<double>(grids[static_cast<std::size_t>(k)]->v[i]) - old[i]);
                maxd[k] = std::max(maxd[k], d);
                sumd[k] += d;
            }
            sumd[k] /= static_cast<double>(old.size());
        }
        std::printf("    vs stored: ambient max %.3g mean %.3g; rgb max %.3g %.3g %.3g\n", maxd[0], sumd[0], maxd[1],
                    maxd[2], maxd[3]);
    }
}

// The modes of `terrain_bench gi`, sharing the options and the folder the
// ground truths are cached in.
class GiSuite {
public:
    GiSuite(const GiOptions& o, const BenchContext& ctx, std::string cacheDir)
        : o_(o), ctx_(ctx), cacheDir_(std::move(cacheDir)) {}
    void accuracy() const;
    void convergence() const;
    void timing() const;
    void explore() const;
    void stages() const;
    void quickAccuracy() const;
    void dems() const;
    void frameTime() const;
    void plotFromCsv() const;
    void cpuStages() const;
    void tileTiming() const;
    void writeDems() const;

private:
    const GiOptions& o_;
    const BenchContext& ctx_;
    const std::string cacheDir_;

    Grid referenceAmbient(const Dem& d, int stride, int border) const;
    Timing timeFrames(const Dem& d, const GiSettings& s, const GiLighting& light, GiState& st, int runs) const;
    void runSettingsRows(const Dem& d, const Grid& ref, int border, std::vector<Row>& rows, int threads) const;
    Timing bestOfThree(const Dem& d, const GiSettings& set, const GiLighting& light, int threads, GiState& st,
                       double& otherLoad) const;
    // The machine, build and command paragraphs of a results file.
    std::string provenance() const {
        return "Machine: " + cpuAndThreads() + ". Build: " + buildFlags() + ".\n\nCommand: `" + ctx_.command +
               "` (from the repository root; references cached for the run, or across runs with --cache DIR).\n\n";
    }
};

// Reference ambient on the interior (10 % border left out), every `stride`-th texel, cached.
Grid GiSuite::referenceAmbient(const Dem& d, int stride, int border) const {
    const std::string cache =
        cacheDir_ + "/gi_reference_" + d.name + "_s" + std::to_string(stride) + "_b" + std::to_string(border) + ".bin";
    Grid g;
    if (readCachedGrids(cache, d.heights.nx, d.heights.ny, {&g, 1})) return g;
    std::fprintf(stderr, "reference for %s (stride %d) ...\n", d.name.c_str(), stride);
    const auto t0 = Clock::now();
    ReferenceSettings rs;
    rs.azimuths = 256;
    rs.border = border;
    rs.stride = stride;
    rs.progress = true;
    ReferenceResult rr;
    renderReference(d.heights.cview(), d.cell, nullptr, nullptr, rs, rr);
    std::fprintf(stderr, "reference: %.1f s\n", std::chrono::duration<double>(Clock::now() - t0).count());
    writeCachedGrids(cache, {&rr.ambient, 1});
    return rr.ambient;
}

// Median over o_.runs frames after one warm-up frame.
Timing GiSuite::timeFrames(const Dem& d, const GiSettings& s, const GiLighting& light, GiState& st, int runs) const {
    runGiFrame(d.heights.cview(), d.cell, light, s, st);
    std::vector<double> tot, pyr, vis, key, sh;
    for (int r = 0; r < runs; ++r) {
        runGiFrame(d.heights.cview(), d.cell, light, s, st);
        tot.push_back(st.timings.total);
        pyr.push_back(st.timings.pyramid + st.timings.gradient);
        vis.push_back(st.timings.visibility);
        key.push_back(st.timings.keyVisibility);
        sh.push_back(st.timings.shading);
    }
    // median, or with --min the minimum (robust to a busy machine while developing)
    const bool useMin = o_.useMin;
    auto med = [useMin](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return useMin ? v.front() : v[v.size() / 2];
    };
    return {med(tot), med(pyr), med(vis), med(key), med(sh)};
}

// quick: alps ambient error of the engine defaults and paper settings at 1x/2x/4x (for trying changes)
void GiSuite::quickAccuracy() const {
    const Dem alps = loadAlps(ctx_.dataDir);
    const int border = alps.heights.nx / 10;
    const Grid ref = referenceAmbient(alps, 1, border);
    for (const char* which : {"paper", "engine"})
        for (int s : {1, 2, 4}) {
            GiSettings set = std::string(which) == "paper" ? paperGiSettings() : GiSettings{};
            set.subsample = s;
            GiState st;
            withThreads(2, [&] {
                runGiFrame(alps.heights.cview(), alps.cell, GiLighting{}, set, st);
                return 0;
            });
            const ErrorStats e = compare(st.shade.ambient, ref, 1, border);
            std::printf("%-6s %dx: rmse %.5f bias %+.5f max %.4f\n", which, s, e.rmse, e.bias, e.maxAbs);
        }
}

// dems: the ambient map on every real DEM measured, the engine's settings at
// 1x/2x/4x against its settings before the exact ambient and the paper's
GiSettings withSubsample(GiSettings s, int subsample) {
    s.subsample = subsample;
    return s;
}

GiSettings engineBeforeExactAmbient() {
    GiSettings s = engineDefaults();
    s.ambient = AmbientMethod::ShProduct;
    s.pyramid.peakBlend = 0.5f;
    return s;
}

void GiSuite::dems() const {
    const std::vector<Dem> dems = realDems(ctx_.dataDir);
    std::string md = "# The ambient map on real DEMs\n\n";
    md +=
        "Ambient = normal-weighted sky-view factor (direct irradiance / pi under a uniform unit sky), against "
        "gi/reference (256 azimuths, exact march of the bilinear field) on the interior (10 % border left out). "
        "\"engine\": GiSettings{} (ambient from the horizons, gi/ambient_horizon.h); \"before\": the same "
        "with the order-4 SH ambient and peak blend 0.5 (the engine before the exact ambient); \"paper\": "
        "paperGiSettings(). Time: whole frame (uniform sky), 2 threads, median of " +
        std::to_string(o_.runs) + " after a warm-up.\n\n" + provenance();
    md += "| DEM | cells | cell (m) | settings | RMSE | bias | max abs | ms |\n|---|---|---|---|---|---|---|---|\n";
    std::string csv =
        "dem,label,azimuths,levels_per_octave,level_offset,blocking_max,peak_blend,subsample,rmse,bias,"
        "max_abs,ms\n";
    for (const Dem& d : dems) {
        const int border = d.heights.nx / 10;
        const Grid ref = referenceAmbient(d, 1, border);
        std::vector<Row> rows;
        for (int s : {1, 2, 4}) rows.push_back({"engine", withSubsample(engineDefaults(), s), {}, {}});
        for (int s : {1, 2}) rows.push_back({"before", withSubsample(engineBeforeExactAmbient(), s), {}, {}});
        rows.push_back({"paper", paperSettings(), {}, {}});
        runSettingsRows(d, ref, border, rows, 2);
        char head[160];
        std::snprintf(head, sizeof head, "| %s | %d x %d | %.2f | ", d.name.c_str(), d.heights.nx, d.heights.ny,
                      static_cast<double>(d.cell));
        for (const Row& r : rows) {
            md += head + r.label + ": " + settingsName(r.s) + " " + errorCells(r);
            csv += d.name + "," + r.label + "," + settingsCsv(r, false);
        }
    }
    writeResult(ctx_.outDir, "gi_ambient_dems.md", md);
    writeResult(ctx_.outDir, "gi_ambient_dems.csv", csv);
}

// frame-time: the whole frame on every real DEM at 1x and 2x, 2 threads, the
// engine against itself before the exact ambient (SH ambient, peak blend
// 0.5), each under a uniform sky (the ambient's own frame: the engine reads
// the horizons alone and computes no SH visibility) and under the sun and
// sky projected on SH (a lighting that reads V in both). Rounds interleave
// the four so that the machine's drift falls on all alike.
void GiSuite::frameTime() const {
    struct Case {
        const char* label;
        GiSettings s;
        GiLighting light;
        std::vector<double> ms;
        GiState st;
    };
    constexpr int kRounds = 3;
    GiLighting shSky;
    shSky.environment = sunSkyLight();
    std::string md = "# Frame time of the exact ambient\n\n";
    md +=
        "Whole GI frame (gradient, pyramid, visibility, ambient, shading), 2 threads, median and interquartile range "
        "of " +
        std::to_string(kRounds * o_.runs) + " frames (" + std::to_string(kRounds) + " interleaved rounds of " +
        std::to_string(o_.runs) +
        " after a warm-up). \"engine\": GiSettings{}; \"before\": the same with the order-4 SH ambient and "
        "peak blend 0.5 (the engine before the exact ambient). Uniform sky: the ambient's own frame (the engine "
        "reads the scan's horizons alone and computes no SH visibility V); SH sky: sunSkyLight() projected on SH, "
        "whose variation goes through the SH product in both, so both compute V. Ratio: engine over before under "
        "the same sky. The ambient maps are those of `gi dems` bit for bit (its errors against the exact reference "
        "hold: gi_ambient_dems.md); a frame that computes no V gives the same outputs as one that does "
        "(tests/test_gi_environment_sh.cpp).\n\n" +
        provenance();
    md +=
        "| DEM | cells | s | sky | engine ms | IQR | before ms | IQR | ratio "
        "|\n|---|---|---|---|---|---|---|---|---|\n";
    std::string csv = "dem,subsample,sky,engine_ms,engine_iqr,before_ms,before_iqr,ratio\n";
    for (const Dem& d : realDems(ctx_.dataDir))
        for (int s : {1, 2}) {
            std::vector<Case> cases;
            cases.push_back({"uniform", withSubsample(engineDefaults(), s), GiLighting{}, {}, {}});
            cases.push_back({"uniform", withSubsample(engineBeforeExactAmbient(), s), GiLighting{}, {}, {}});
            cases.push_back({"SH", withSubsample(engineDefaults(), s), shSky, {}, {}});
            cases.push_back({"SH", withSubsample(engineBeforeExactAmbient(), s), shSky, {}, {}});
            withThreads(2, [&] {
                for (Case& c : cases) runGiFrame(d.heights.cview(), d.cell, c.light, c.s, c.st);
                for (int round = 0; round < kRounds; ++round)
                    for (Case& c : cases)
                        for (int r = 0; r < o_.runs; ++r) {
                            runGiFrame(d.heights.cview(), d.cell, c.light, c.s, c.st);
                            c.ms.push_back(c.st.timings.total);
                        }
                return 0;
            });
            for (std::size_t k = 0; k < cases.size(); k += 2) {
                const Spread e = spreadOf(cases[k].ms), b = spreadOf(cases[k + 1].ms);
                md += fmt("| %s | %d x %d | %dx | %s | %.1f | %.1f | %.1f | %.1f | %.2fx |\n", d.name.c_str(),
                          d.heights.nx, d.heights.ny, s, cases[k].label, e.median, e.iqr(), b.median, b.iqr(),
                          e.median / b.median);
                const std::string row = fmt("%s,%d,%s,%.2f,%.2f,%.2f,%.2f,%.3f\n", d.name.c_str(), s, cases[k].label,
                                            e.median, e.iqr(), b.median, b.iqr(), e.median / b.median);
                csv += row;
                std::fprintf(stderr, "%s", row.c_str());
            }
        }
    writeResult(ctx_.outDir, "gi_frame_time.md", md);
    writeResult(ctx_.outDir, "gi_frame_time.csv", csv);
}

// write-dems: the real DEMs of frame-time as float32 EXR heightmaps (one
// `height` channel, the cell size in `terrain:cellSize`) and a list of their
// names and cell sizes, dems.txt, so that another build's CLI can light the
// same fields (bench/frame_time_against_build.sh).
void GiSuite::writeDems() const {
    std::string list;
    std::filesystem::create_directories(ctx_.outDir);
    for (const Dem& d : realDems(ctx_.dataDir)) {
        const std::string file = d.name + ".exr";
        writeExrChannels(ctx_.outDir + "/" + file, {"height"}, {&d.heights}, d.cell);
        list += fmt("%s %.6f\n", file.c_str(), static_cast<double>(d.cell));
    }
    writeResult(ctx_.outDir, "dems.txt", list);
}

void GiSuite::runSettingsRows(const Dem& d, const Grid& ref, int border, std::vector<Row>& rows, int threads) const {
    for (Row& r : rows) {
        GiState st;
        withThreads(threads, [&] {
            r.t = timeFrames(d, r.s, GiLighting{}, st, o_.runs);
            return 0;
        });
        r.e = compare(st.shade.ambient, ref, 1, border);
        std::fprintf(stderr, "%-60s rmse %.4f bias %+.4f max %.3f  %.1f ms\n",
                     (r.label + " " + settingsName(r.s)).c_str(), r.e.rmse, r.e.bias, r.e.maxAbs, r.t.median);
    }
}

void GiSuite::accuracy() const {
    const Dem alps = loadAlps(ctx_.dataDir);
    const int border = alps.heights.nx / 10;
    const Grid ref = referenceAmbient(alps, 1, border);
    std::vector<Row> rows;
    rows.push_back({"paper settings", paperSettings(), {}, {}});
    rows.push_back({"engine defaults", engineDefaults(), {}, {}});
    runSettingsRows(alps, ref, border, rows, 2);
    std::string md = "# GI ambient accuracy on alps-montblanc (true scale)\n\n";
    md += "DEM: ../shared/data/alps-montblanc.png, 647 x 647, cell 92.74 m, heights 454..4810 m. ";
    md += "Interior only: a 64-texel (10 %) border is left out (" + std::to_string(rows[0].e.count) + " texels). ";
    md += "Ground truth: gi/reference (256 azimuths, exact march of the bilinear field, exact elevation integrals). ";
    md += "Ambient = direct irradiance / pi under a uniform unit sky (normal-weighted sky-view factor). ";
    md +=
        "Time: whole frame (gradient, pyramid, visibility, shading; uniform sky, no key light) with 2 threads, median "
        "of " +
        std::to_string(o_.runs) + " after a warm-up.\n\n" + provenance();
    md += "| settings | RMSE | bias | max abs | ms/frame |\n|---|---|---|---|---|\n";
    std::string csv =
        "label,azimuths,levels_per_octave,level_offset,interp,blocking_max,peak_blend,subsample,rmse,bias,max_abs,ms\n";
    for (const Row& r : rows) {
        md += "| " + r.label + ": " + settingsName(r.s) + " " + errorCells(r);
        csv += r.label + "," + settingsCsv(r, true);
    }
    writeResult(ctx_.outDir, "gi_accuracy.md", md);
    writeResult(ctx_.outDir, "gi_accuracy.csv", csv);
}

// ---------------------------------------------------------------------------
// explore: many settings (used to choose the defaults)
// ---------------------------------------------------------------------------
void GiSuite::explore() const {
    const Dem alps = loadAlps(ctx_.dataDir);
    const int border = alps.heights.nx / 10;
    const Grid ref = referenceAmbient(alps, 1, border);
    std::vector<Row> rows;
    for (int o : {2, 3, 4, 5})
        for (float peak : {0.0f, 0.5f, 1.0f})
            for (BlockingMax bm : {BlockingMax::BsplineKnotsAndMidpoints, BlockingMax::Samples}) {
                GiSettings s = engineDefaults();
                s.pyramid.levelOffset = o;
                s.pyramid.peakBlend = peak;
                s.visibility.blockingMax = bm;
                rows.push_back({"explore", s, {}, {}});
            }
    for (int k : {4, 6, 8})
        for (int m : {16, 24, 32, 48}) {
            GiSettings s = engineDefaults();
            s.pyramid.levelsPerOctave = k;
            s.visibility.azimuths = m;
            rows.push_back({"explore", s, {}, {}});
        }
    runSettingsRows(alps, ref, border, rows, 2);
    std::string csv =
        "azimuths,levels_per_octave,level_offset,interp,blocking_max,peak_blend,subsample,rmse,bias,max_abs,ms\n";
    for (const Row& r : rows) csv += settingsCsv(r, true);
    writeResult(ctx_.outDir, "gi_explore.csv", csv);
}

// ---------------------------------------------------------------------------
// convergence: error vs m, k_v, o_v and sub-sampling on a small terrain
// ---------------------------------------------------------------------------
void GiSuite::convergence() const {
    const Dem alps = loadAlps(ctx_.dataDir);
    const Dem small = cropDem(alps, 256, "c256");
    const int border = small.heights.nx / 10;
    const Grid ref = referenceAmbient(small, 1, border);
    std::vector<Row> rows;
    auto base = [] {
        GiSettings s = wholeFrames(paperGiSettings());
        s.visibility.blockingMax = BlockingMax::Samples;
        return s;
    };
    for (int m : {8, 16, 32, 64, 128}) {
        GiSettings s = base();
        s.visibility.azimuths = m;
        s.pyramid.levelsPerOctave = 8;
        s.pyramid.levelOffset = 6;
        rows.push_back({"vary m (k_v=8, o_v=6)", s, {}, {}});
    }
    for (int k : {1, 2, 4, 8, 16}) {
        GiSettings s = base();
        s.visibility.azimuths = 128;
        s.pyramid.levelsPerOctave = k;
        s.pyramid.levelOffset = 6;
        rows.push_back({"vary k_v (m=128, o_v=6)", s, {}, {}});
    }
    for (int o : {0, 1, 2, 3, 4, 6}) {
        GiSettings s = base();
        s.visibility.azimuths = 128;
        s.pyramid.levelsPerOctave = 8;
        s.pyramid.levelOffset = o;
        rows.push_back({"vary o_v (m=128, k_v=8)", s, {}, {}});
    }
    for (const char* which : {"paper", "engine"})
        for (int sub : {4, 2, 1}) {
            GiSettings s = std::string(which) == "paper" ? paperSettings() : engineDefaults();
            s.subsample = sub;
            rows.push_back({std::string("sub-sampling, ") + which + " settings", s, {}, {}});
        }
    runSettingsRows(small, ref, border, rows, 2);
    std::string md = "# GI convergence to the ground truth (small terrain)\n\n";
    md +=
        "Terrain: alps-montblanc centre crop 256 x 256 at true scale (cell 92.74 m), interior only (25-texel border "
        "left out, " +
        std::to_string(rows[0].e.count) +
        " texels). Ambient RMSE / bias against gi/reference (256 azimuths, exact march "
        "of the bilinear field, exact elevation integrals). The m / k_v / o_v sweeps use the plain sample maximum (the "
        "B-spline maximum of Eq. 16 smooths the blocking-angle sequence and does not converge to the exact horizon); "
        "what remains at large m, k_v, o_v is the order-4 SH truncation of visibility (and m = 128 azimuth "
        "interpolation). "
        "Sub-sampling rows: the paper settings (" +
        directSettingsText(paperSettings()) + ") and the engine defaults (" + directSettingsText(engineDefaults()) +
        "), 4x -> 2x -> 1x. Times: whole frame (uniform sky, no key "
        "light), 2 threads, median of " +
        std::to_string(o_.runs) + ".\n\n" + provenance();
    md += "| sweep | settings | RMSE | bias | max abs | ms/frame |\n|---|---|---|---|---|---|\n";
    std::string csv =
        "sweep,azimuths,levels_per_octave,level_offset,blocking_max,peak_blend,subsample,rmse,bias,max_abs,ms\n";
    for (const Row& r : rows) {
        md += "| " + r.label + " | " + settingsName(r.s) + " " + errorCells(r);
        csv += r.label + "," + settingsCsv(r, false);
    }
    writeResult(ctx_.outDir, "gi_convergence.md", md);
    writeResult(ctx_.outDir, "gi_convergence.csv", csv);
}

// The machine is shared (2 vCPUs, other people's builds): each row is measured
// 3 times (median of o_.runs frames each) and the lowest median kept; a repeat
// during which other processes used more than 5 % of a core (/proc/stat minus
// our own CPU time) is re-done, up to 6 extra times. otherLoad: that of the kept
// repeat, in cores; st: the state of the last frame.
Timing GiSuite::bestOfThree(const Dem& d, const GiSettings& set, const GiLighting& light, int threads, GiState& st,
                            double& otherLoad) const {
    Timing t;
    Timing best;
    best.median = 1e30;
    for (int good = 0, attempt = 0; good < 3 && attempt < 9; ++attempt) {
        const double busy0 = machineBusySeconds(), own0 = processCpuSeconds();
        const auto w0 = Clock::now();
        withThreads(threads, [&] {
            t = timeFrames(d, set, light, st, o_.runs);
            return 0;
        });
        const double wall = std::chrono::duration<double>(Clock::now() - w0).count();
        const double other = std::max(0.0, (machineBusySeconds() - busy0) - (processCpuSeconds() - own0)) / wall;
        if (other >= 0.05 && attempt < 8) {
            std::fprintf(stderr, "busy machine (other load %.2f cores), re-measuring\n", other);
            std::this_thread::sleep_for(std::chrono::seconds(2));
            continue;
        }
        ++good;
        if (t.median < best.median) {
            best = t;
            otherLoad = other;
        }
    }
    return best;
}

// ---------------------------------------------------------------------------
// timing: 256^2, 512^2, 1024^2 x 1x/2x/4x x 1/2 threads, one env + one key light
// ---------------------------------------------------------------------------
void GiSuite::timing() const {
    const Dem alps = loadAlps(ctx_.dataDir);
    const Dem perdu = loadPerdu(ctx_.dataDir);
    struct Size {
        Dem dem;
        std::string source;
    };
    std::vector<Size> sizes;
    sizes.push_back({cropDem(alps, 256, "c256"), "alps c256"});
    sizes.push_back({cropDem(alps, 512, "c512"), "alps c512"});
    sizes.push_back({cropDem(perdu, 1024, "c1024"), "mtperdu c1024"});
    const GiLighting light = sunSkyAndKey();
    std::string md = "# GI time per frame\n\n";
    md +=
        "Frame = gradient + pyramid + environment visibility + key-light visibility + direct shading (Lambert, RGB + "
        "ambient "
        "map), one sun-and-sky environment light (m azimuths) and one key light (3 azimuths over its extent), as "
        "`terrain gi --frames N --time` runs it. Median of " +
        std::to_string(o_.runs) +
        " frames after a warm-up (best of 3 repeats, below); stage columns are medians too (ms).\n\n"
        "DEMs (centre crops at true scale, no resampling): 256^2 and 512^2 = ../shared/data/alps-montblanc.png (cell "
        "92.74 m), "
        "1024^2 = ../shared/data/mtperdu_20m.png (cell 20 m).\n\n"
        "Error: ambient map (normal-weighted sky-view factor) RMSE / bias against gi/reference (256 azimuths, exact "
        "march) "
        "over the interior (10 % border left out); at 1024^2 over every 4th texel in x and y of the interior (the "
        "reference is computed and cached only there). The error does not depend on the thread count.\n\n"
        "Settings: paper = " +
        directSettingsText(paperSettings()) + "; engine = the engine defaults (" +
        directSettingsText(engineDefaults()) +
        "). pyramid = gradient + pyramid.\n\nThe machine is shared with other work (2 vCPUs): "
        "each row is measured 3 times (median of " +
        std::to_string(o_.runs) +
        " frames each) and the lowest of the 3 medians is "
        "reported with its stage medians; a repeat during which other processes used more than 5 % of a core is "
        "discarded "
        "and re-done (other load = other processes' CPU time over the kept repeat, from /proc/stat, in cores). Load on "
        "the "
        "other vCPU of a shared physical core does not show in /proc/stat, so single rows can still be noisy.\n\n" +
        provenance();
    md +=
        "| DEM | size | sub | settings | threads | ms/frame | pyramid | visibility | key light | shading | RMSE | bias "
        "| other load |\n";
    md += "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    std::string csv =
        "dem,size,subsample,settings,threads,ms,pyramid_ms,visibility_ms,key_ms,shading_ms,rmse,bias,other_load\n";
    for (const Size& sz : sizes) {
        const int n = sz.dem.heights.nx;
        const int border = n / 10;
        const int stride = n >= 1024 ? 4 : 1;
        const Grid ref = referenceAmbient(sz.dem, stride, border);
        for (const char* which : {"paper", "engine"})
            for (int s : {1, 2, 4})
                for (int threads : {1, 2}) {
                    GiSettings set = std::string(which) == "paper" ? paperSettings() : engineDefaults();
                    set.subsample = s;
                    GiState st;
                    double otherLoad = 0.0;
                    const Timing t = bestOfThree(sz.dem, set, light, threads, st, otherLoad);
                    const ErrorStats e = compare(st.shade.ambient, ref, stride, border);
                    char buf[600];
                    std::snprintf(
                        buf, sizeof buf,
                        "| %s | %d | %dx | %s | %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.4f | %+.4f | %.2f |\n",
                        sz.source.c_str(), n, s, which, threads, t.median, t.pyramid, t.visibility, t.key, t.shading,
                        e.rmse, e.bias, otherLoad);
                    md += buf;
                    std::snprintf(buf, sizeof buf, "%s,%d,%d,%s,%d,%.2f,%.2f,%.2f,%.2f,%.2f,%.5f,%.5f,%.3f\n",
                                  sz.dem.name.c_str(), n, s, which, threads, t.median, t.pyramid, t.visibility, t.key,
                                  t.shading, e.rmse, e.bias, otherLoad);
                    csv += buf;
                    std::fprintf(stderr, "%s %d %dx %s %dT: %.1f ms (rmse %.4f)\n", sz.dem.name.c_str(), n, s, which,
                                 threads, t.median, e.rmse);
                }
    }
    md += "\n![speed vs error](gi_speed_error.png)\n";
    writeResult(ctx_.outDir, "gi_timing.md", md);
    writeResult(ctx_.outDir, "gi_timing.csv", csv);
    drawPlot(ctx_, "gi_speed_error");
}

// plot only: redraws gi_speed_error.png / .svg from the gi_timing.csv in the results folder
void GiSuite::plotFromCsv() const { drawPlot(ctx_, "gi_speed_error"); }

// ---------------------------------------------------------------------------
// stages: per-stage times of the target frames, 512^2 at 2x and 647^2 at 1x (a quick check while optimising)
// ---------------------------------------------------------------------------
void GiSuite::stages() const {
    const Dem alps = loadAlps(ctx_.dataDir);
    const GiLighting light = sunSkyAndKey();
    struct Case {
        const Dem* dem;
        int s;
        const char* which;
    };
    const Dem c512 = cropDem(alps, 512, "c512");
    int caseIndex = -1;
    for (const Case& c :
         {Case{&c512, 2, "engine"}, Case{&c512, 2, "paper"}, Case{&alps, 1, "engine"}, Case{&alps, 1, "paper"}}) {
        ++caseIndex;
        if (o_.onlyCase >= 0 && o_.onlyCase != caseIndex) continue;  // one case only
        GiSettings set = std::string(c.which) == "paper" ? paperSettings() : engineDefaults();
        set.subsample = c.s;
        GiState st;
        Timing t;
        const int threads = o_.threads;
        timespec c0{}, c1{};
        withThreads(threads, [&] {
            t = timeFrames(*c.dem, set, light, st, o_.runs);
            clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
            runGiFrame(c.dem->heights.cview(), c.dem->cell, light, set, st);
            clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
            return 0;
        });
        const double cpu = (c1.tv_sec - c0.tv_sec) * 1e3 + (c1.tv_nsec - c0.tv_nsec) * 1e-6;
        std::printf(
            "%-22s %dx %-6s %dT: %6.1f ms, cpu %6.1f ms (pyramid+grad %.1f, visibility %.1f, key %.1f, shading %.1f)\n",
            c.dem->name.c_str(), c.s, c.which, threads, t.median, cpu, t.pyramid, t.visibility, t.key, t.shading);
        // --dump write stores the outputs, --dump compare reports the largest change against them
        if (!o_.dump.empty()) {
            const std::string file =
                cacheDir_ + "/gi_stage_" + c.dem->name + "_" + std::to_string(c.s) + c.which + ".bin";
            storeOrCompare(o_.dump, file, {&st.shade.ambient, &st.shade.rgb[0], &st.shade.rgb[1], &st.shade.rgb[2]});
        }
    }
}

// ---------------------------------------------------------------------------
// cpu: CPU time per stage, one thread, minimum over runs (robust on a busy machine)
// ---------------------------------------------------------------------------
double threadCpuMs() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

void GiSuite::cpuStages() const {
    const Dem alps = loadAlps(ctx_.dataDir);
    const Dem c512 = cropDem(alps, 512, "c512");
    const GiLighting light = sunSkyAndKey();
    struct Case {
        const Dem* dem;
        int s;
        const char* which;
    };
    int caseIndex = -1;
    for (const Case& c : {Case{&c512, 2, "engine"}, Case{&c512, 2, "paper"}, Case{&alps, 1, "engine"}}) {
        ++caseIndex;
        if (o_.onlyCase >= 0 && o_.onlyCase != caseIndex) continue;
        GiSettings set = std::string(c.which) == "paper" ? paperSettings() : engineDefaults();
        set.subsample = c.s;
        withThreads(1, [&] {
            GiState st;
            runGiFrame(c.dem->heights.cview(), c.dem->cell, light, set, st);
            double best[5] = {1e30, 1e30, 1e30, 1e30, 1e30};
            for (int r = 0; r < o_.runs; ++r) {
                double t0 = threadCpuMs();
                computeGradient(c.dem->heights.cview(), c.dem->cell, st.gradX, st.gradY);
                buildHeightPyramid(c.dem->heights.cview(), c.dem->cell, set.subsample, set.pyramid, st.pyramid);
                double t1 = threadCpuMs();
                VisibilityTarget env;
                env.op = &st.envOperator;
                computeVisibility(st.pyramid, st.gradX.cview(), st.gradY.cview(), set.visibility, env,
                                  st.visibilityState, st.envVisibility);
                double t2 = threadCpuMs();
                runGiFrame(c.dem->heights.cview(), c.dem->cell, light, set, st);
                double t3 = threadCpuMs();
                best[0] = std::min(best[0], t1 - t0);
                best[1] = std::min(best[1], t2 - t1);
                best[2] = std::min(best[2], t3 - t2);
                best[3] = std::min(best[3], st.timings.keyVisibility);
                best[4] = std::min(best[4], st.timings.shading);
            }
            std::printf(
                "%-22s %dx %-6s cpu: grad+pyramid %.1f  env visibility %.1f  frame %.1f  (wall key %.1f shading "
                "%.1f)\n",
                c.dem->name.c_str(), c.s, c.which, best[0], best[1], best[2], best[3], best[4]);
            return 0;
        });
    }
}

// ---------------------------------------------------------------------------
// tiles: computeVisibility restricted to receiver tiles (change-driven GI)
// against the whole grid, 512^2 at 2x, engine settings, the environment's V
// ---------------------------------------------------------------------------
// A fraction of the tiles dirty: scattered at random, or one square cluster
// in the middle (a local change).
void pickDirtyTiles(double fraction, bool clustered, std::mt19937& rng, ReceiverTiles& t) {
    std::fill(t.dirty.begin(), t.dirty.end(), 0);
    const int n = std::max(1, static_cast<int>(std::lround(fraction * t.tilesX * t.tilesY)));
    if (clustered) {
        const int side = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<double>(n)))));
        const int tx0 = (t.tilesX - side) / 2, ty0 = (t.tilesY - side) / 2;
        for (int k = 0; k < n; ++k) t.setDirty(tx0 + k % side, ty0 + k / side);
        return;
    }
    std::vector<int> order(t.dirty.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
    std::shuffle(order.begin(), order.end(), rng);
    for (int k = 0; k < n; ++k) t.dirty[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])] = 1;
}

void GiSuite::tileTiming() const {
    const Dem c512 = cropDem(loadAlps(ctx_.dataDir), 512, "c512");
    GiSettings set = engineDefaults();
    set.subsample = 2;
    GiState st;
    withThreads(o_.threads, [&] { runGiFrame(c512.heights.cview(), c512.cell, GiLighting{}, set, st); });
    VisibilityTarget env;
    env.op = &st.envOperator;
    env.footprint = &st.footprint;
    const auto time = [&](const ReceiverTiles* only) {
        std::vector<double> ms;
        withThreads(o_.threads, [&] {
            for (int r = 0; r < o_.runs + 1; ++r) {
                const auto t0 = Clock::now();
                computeVisibility(st.pyramid, st.gradX.cview(), st.gradY.cview(), set.visibility, env,
                                  st.visibilityState, st.envVisibility, only);
                const double t = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
                if (r > 0) ms.push_back(t);  // the first run warms up
            }
        });
        return ms;
    };
    const auto report = [&](const char* what, const ReceiverTiles* only) {
        const std::vector<double> ms = time(only);
        const double share = only ? 100.0 * only->dirtyFraction() : 100.0;
        std::printf("%-34s receivers %5.1f %%  median %7.2f ms  min %7.2f ms\n", what, share, median(ms),
                    *std::min_element(ms.begin(), ms.end()));
    };
    std::printf("computeVisibility, %s 2x (%d x %d receivers), %d threads, %d runs\n", c512.name.c_str(),
                st.pyramid.nxr, st.pyramid.nyr, o_.threads, o_.runs);
    report("no tiles (whole grid)", nullptr);
    std::mt19937 rng(1);
    for (int size : {16, 32}) {
        ReceiverTiles t;
        t.reset(st.pyramid.nxr, st.pyramid.nyr, size, true);
        report(("tiles " + std::to_string(size) + ": all dirty").c_str(), &t);
        for (double f : {0.5, 0.1, 0.01})
            for (bool clustered : {false, true}) {
                pickDirtyTiles(f, clustered, rng, t);
                const std::string what = "tiles " + std::to_string(size) + ": " + std::to_string(t.dirtyCount()) +
                                         " / " + std::to_string(t.dirty.size()) +
                                         (clustered ? " clustered" : " random");
                report(what.c_str(), &t);
            }
    }
}

struct Mode {
    const char* name;
    const char* help;
    void (GiSuite::*run)() const;
};

const Mode kModes[] = {
    {"accuracy", "Paper settings vs engine defaults on Mont Blanc at true scale (gi_accuracy.md, .csv)",
     &GiSuite::accuracy},
    {"convergence", "Error vs m, k_v, o_v and sub-sampling on a 256^2 crop (gi_convergence.md, .csv)",
     &GiSuite::convergence},
    {"timing", "Time per frame, 256^2..1024^2 x 1x/2x/4x x 1/2 threads (gi_timing.md, .csv, gi_speed_error.png, .svg)",
     &GiSuite::timing},
    {"explore", "Many settings, to choose the defaults (gi_explore.csv)", &GiSuite::explore},
    {"stages", "Per-stage times of the target frames (stdout; a quick check while optimising)", &GiSuite::stages},
    {"quick", "Ambient error of the paper and engine settings at 1x/2x/4x (stdout; for trying changes)",
     &GiSuite::quickAccuracy},
    {"dems", "Ambient error and time on every real DEM, engine vs before vs paper (gi_ambient_dems.md, .csv)",
     &GiSuite::dems},
    {"frame-time",
     "Whole-frame time on every real DEM at 1x/2x: engine vs before the exact ambient, uniform and SH sky "
     "(gi_frame_time.md, .csv)",
     &GiSuite::frameTime},
    {"plot", "Only redraw gi_speed_error.png and .svg from an existing gi_timing.csv (bench/plots/gi_speed_error.py)",
     &GiSuite::plotFromCsv},
    {"cpu", "CPU time per stage, one thread, minimum over the runs (stdout)", &GiSuite::cpuStages},
    {"tiles", "computeVisibility with receiver tiles (1 %, 10 %, 50 %, all dirty) vs the whole grid (stdout)",
     &GiSuite::tileTiming},
    {"write-dems",
     "Write the real DEMs of frame-time as float EXR heightmaps and dems.txt (names, cell sizes) to --out, for "
     "bench/frame_time_against_build.sh",
     &GiSuite::writeDems},
};

int runGi(const CLI::App& sub, const GiOptions& o, const BenchContext& ctx) {
    if (!o.dump.empty() && o.cacheDir.empty())
        throw InputError("--dump needs --cache DIR, where the outputs outlive the run");
    std::optional<ScratchDir> scratch;
    if (o.cacheDir.empty()) scratch.emplace();
    const GiSuite suite(o, ctx, scratch ? scratch->path() : o.cacheDir);
    std::vector<std::string> modes;
    for (const CLI::App* m : sub.get_subcommands()) modes.push_back(m->get_name());
    if (modes.empty()) modes = {"accuracy", "convergence", "timing"};
    for (const std::string& name : modes)
        for (const Mode& m : kModes)
            if (name == m.name) (suite.*m.run)();
    return 0;
}

}  // namespace

Runner addGiSuite(CLI::App& app, const BenchContext& ctx) {
    auto o = std::make_shared<GiOptions>();
    CLI::App* sub = app.add_subcommand("gi",
                                       "GI fast path vs ground truth: accuracy, convergence, time per frame "
                                       "(default: accuracy convergence timing)");
    sub->require_subcommand(0, 0);  // any number of modes, run in the order given
    addRunsOption(*sub, o->runs, "Frames per timing after a warm-up");
    sub->add_flag("--min", o->useMin, "Report the fastest frame, not the median (a busy machine while developing)")
        ->envname("GI_MIN");
    sub->add_option("--cache", o->cacheDir, "Folder to keep the ground truths in across runs (default: none)")
        ->envname("GI_CACHE_DIR");
    for (const Mode& m : kModes) {
        CLI::App* mode = sub->add_subcommand(m.name, m.help);
        const std::string name = m.name;
        if (name == "stages" || name == "cpu")
            mode->add_option("--case", o->onlyCase, "Only this case (0-based; -1: all)")
                ->envname("GI_CASE")
                ->capture_default_str();
        if (name == "stages" || name == "tiles")
            mode->add_option("--threads", o->threads, "Worker threads")->envname("GI_THREADS")->capture_default_str();
        if (name == "stages") {
            mode->add_option("--dump", o->dump,
                             "write: store the outputs in the --cache folder; compare: the change against them")
                ->envname("GI_DUMP")
                ->check(CLI::IsMember({"write", "compare"}));
        }
    }
    return [o, sub, &ctx] { return runGi(*sub, *o, ctx); };
}

}  // namespace terrain::bench
