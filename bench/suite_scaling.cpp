// `terrain_bench scaling`: how the time of a whole GI frame grows with the
// number of cells and with the number of azimuths, at 1 and 2 threads.
// Frames: the initial ground of builtinScene("erosion", N, 1), the engine's
// default GI settings with one bounce and 2x sub-sampling, sun-and-sky plus
// one key light, uniform albedo (the frames of the table1 suite), whole
// frames (no incremental caching). The exponents of time against cells and
// against azimuths are fitted by least squares on log-log axes. Writes
// scaling.md, scaling.csv, scaling_fit.csv and scaling.png / .svg
// (bench/plots/scaling.py).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

#include "bench/suites.h"
#include "core/error.h"
#include "core/parallel.h"
#include "gi/frame.h"

namespace terrain::bench {
namespace {

struct ScalingOptions {
    int runs = 7;
    std::vector<int> sizes = {128, 256, 512, 1024, 2048};
    int subsample = 2;
    std::vector<int> azimuths = {8, 16, 32, 64};
    int azimuthSize = 512;
    std::vector<int> threads = {1, 2};
    int fitFrom = 256;  // the smallest size the fit against cells uses
};

// What one row sweeps: the grid size, the environment visibility's m, or the
// indirect scan's azimuths.
enum class Sweep { Cells, EnvAzimuths, IndirectAzimuths };

const char* sweepName(Sweep s) {
    switch (s) {
        case Sweep::Cells:
            return "cells";
        case Sweep::EnvAzimuths:
            return "env_azimuths";
        case Sweep::IndirectAzimuths:
            return "indirect_azimuths";
    }
    return "";
}

// Medians over the measured frames (ms): the frame and GiState::timings'
// stages; and the cores the process had: its CPU time over the wall time of
// the measured frames (below the thread count: other work took the cores).
struct FrameMs {
    double total = 0.0, gradient = 0.0, pyramid = 0.0, visibility = 0.0, key = 0.0, shading = 0.0, indirect = 0.0;
    double totalQ1 = 0.0, totalQ3 = 0.0;  // quartiles of the whole frame's time
    double cores = 0.0;
};

double processCpuSeconds() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

struct Row {
    Sweep sweep = Sweep::Cells;
    int size = 0, envAzimuths = 0, indirectAzimuths = 0, threads = 0;
    FrameMs ms;
    double cells() const { return static_cast<double>(size) * size; }
    // the swept variable: cells, or the azimuths of the swept scan
    double x() const {
        return sweep == Sweep::Cells ? cells() : sweep == Sweep::EnvAzimuths ? envAzimuths : indirectAzimuths;
    }
};

gi::GiSettings frameSettings(const ScalingOptions& o) {
    gi::GiSettings s = wholeFrames(gi::GiSettings{});
    s.subsample = o.subsample;
    s.indirect.bounces = 1;
    return s;
}

// Median of o.runs frames after one warm-up frame, with `threads` workers.
FrameMs timeFrames(const Dem& d, const gi::GiSettings& s, int threads, int runs) {
    const gi::GiLighting light = sunSkyAndBenchKey();
    const gi::AlbedoMap albedo = gi::uniformAlbedo(d.heights.nx, d.heights.ny, 0.6f);
    std::array<std::vector<double>, 7> t;
    double cpu = 0.0, wall = 0.0;
    withThreads(threads, [&] {
        gi::GiState st;
        gi::runGiFrame(d.heights.cview(), d.cell, light, s, st, &albedo);  // warm-up: allocations, operators
        const double cpu0 = processCpuSeconds();
        const auto wall0 = std::chrono::steady_clock::now();
        for (int f = 0; f < runs; ++f) {
            gi::runGiFrame(d.heights.cview(), d.cell, light, s, st, &albedo);
            const gi::GiTimings& g = st.timings;
            const double v[7] = {g.total, g.gradient, g.pyramid, g.visibility, g.keyVisibility, g.shading, g.indirect};
            for (std::size_t k = 0; k < t.size(); ++k) t[k].push_back(v[k]);
        }
        cpu = processCpuSeconds() - cpu0;
        wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    });
    FrameMs ms{median(t[0]), median(t[1]), median(t[2]), median(t[3]), median(t[4]), median(t[5]), median(t[6])};
    const Spread total = spreadOf(t[0]);
    ms.totalQ1 = total.q1;
    ms.totalQ3 = total.q3;
    ms.cores = cpu / wall;
    return ms;
}

Row measure(const Dem& d, Sweep sweep, const gi::GiSettings& s, int threads, int runs) {
    Row r{sweep, d.heights.nx, s.visibility.azimuths, s.indirect.azimuths, threads, {}};
    std::fprintf(stderr, "  %s: %d^2, m %d, indirect azimuths %d, %d thread(s), %d frames + warm-up ...",
                 sweepName(sweep), r.size, r.envAzimuths, r.indirectAzimuths, threads, runs);
    std::fflush(stderr);
    r.ms = timeFrames(d, s, threads, runs);
    std::fprintf(stderr, " %.1f ms (%.2f cores)\n", r.ms.total, r.ms.cores);
    return r;
}

std::vector<Row> sweepCells(const ScalingOptions& o) {
    std::vector<Row> rows;
    for (int n : o.sizes) {
        const Dem d = erodedScene(n, 0);
        for (int threads : o.threads) rows.push_back(measure(d, Sweep::Cells, frameSettings(o), threads, o.runs));
    }
    return rows;
}

std::vector<Row> sweepAzimuths(const ScalingOptions& o) {
    std::vector<Row> rows;
    const Dem d = erodedScene(o.azimuthSize, 0);
    for (Sweep sweep : {Sweep::EnvAzimuths, Sweep::IndirectAzimuths})
        for (int m : o.azimuths)
            for (int threads : o.threads) {
                gi::GiSettings s = frameSettings(o);
                (sweep == Sweep::EnvAzimuths ? s.visibility.azimuths : s.indirect.azimuths) = m;
                rows.push_back(measure(d, sweep, s, threads, o.runs));
            }
    return rows;
}

// time = prefactor * x^exponent, least squares on log-log over the rows of
// one sweep and thread count whose x is at least minX; from and to are the
// smallest and largest x fitted.
struct Fit {
    Sweep sweep = Sweep::Cells;
    int threads = 0;
    double from = 0.0, to = 0.0, exponent = 0.0, prefactor = 0.0;
    int points = 0;
};

Fit fitPowerLaw(const std::vector<Row>& rows, Sweep sweep, int threads, double minX) {
    Fit f{sweep, threads, 1e300, 0.0};
    double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
    for (const Row& r : rows)
        if (r.sweep == sweep && r.threads == threads && r.x() >= minX) {
            f.from = std::min(f.from, r.x());
            f.to = std::max(f.to, r.x());
            const double x = std::log(r.x()), y = std::log(r.ms.total);
            sx += x;
            sy += y;
            sxx += x * x;
            sxy += x * y;
            ++f.points;
        }
    if (f.points == 0) f.from = 0.0;
    const double n = f.points, den = n * sxx - sx * sx;
    if (f.points < 2 || den <= 0.0) return f;  // no fit: exponent stays 0, points says why
    f.exponent = (n * sxy - sx * sy) / den;
    f.prefactor = std::exp((sy - f.exponent * sx) / n);
    return f;
}

std::vector<Fit> fitAll(const std::vector<Row>& rows, const ScalingOptions& o) {
    std::vector<Fit> fits;
    const double lo = static_cast<double>(o.fitFrom) * o.fitFrom;
    for (int threads : o.threads) fits.push_back(fitPowerLaw(rows, Sweep::Cells, threads, lo));
    for (Sweep sweep : {Sweep::EnvAzimuths, Sweep::IndirectAzimuths})
        for (int threads : o.threads) fits.push_back(fitPowerLaw(rows, sweep, threads, 0.0));
    return fits;
}

std::string csvText(const std::vector<Row>& rows, int subsample) {
    std::string csv =
        "sweep,size,subsample,cells,env_azimuths,indirect_azimuths,threads,ms,gradient_ms,pyramid_ms,visibility_ms,key_"
        "ms,"
        "shading_ms,indirect_ms,cores,ms_q1,ms_q3\n";
    for (const Row& r : rows)
        csv += fmt("%s,%d,%d,%.0f,%d,%d,%d,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.2f,%.3f,%.3f\n", sweepName(r.sweep),
                   r.size, subsample, r.cells(), r.envAzimuths, r.indirectAzimuths, r.threads, r.ms.total,
                   r.ms.gradient, r.ms.pyramid, r.ms.visibility, r.ms.key, r.ms.shading, r.ms.indirect, r.ms.cores,
                   r.ms.totalQ1, r.ms.totalQ3);
    return csv;
}

std::string fitCsvText(const std::vector<Fit>& fits) {
    std::string csv = "sweep,threads,x_from,x_to,points,exponent,prefactor_ms\n";
    for (const Fit& f : fits)
        csv += fmt("%s,%d,%.0f,%.0f,%d,%.4f,%.6g\n", sweepName(f.sweep), f.threads, f.from, f.to, f.points, f.exponent,
                   f.prefactor);
    return csv;
}

std::string rowsTable(const std::vector<Row>& rows, Sweep sweep) {
    std::string md =
        sweep == Sweep::Cells ? "| size | cells | threads |" : "| size | m | indirect azimuths | threads |";
    md +=
        " ms / frame | IQR | gradient | pyramid | visibility | key | shading | indirect | ns / cell | cores |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|";
    md += sweep == Sweep::Cells ? "\n" : "---|\n";
    for (const Row& r : rows) {
        if (r.sweep != sweep) continue;
        md += sweep == Sweep::Cells
                  ? fmt("| %d² | %.0f | %d |", r.size, r.cells(), r.threads)
                  : fmt("| %d² | %d | %d | %d |", r.size, r.envAzimuths, r.indirectAzimuths, r.threads);
        md += fmt(" %.1f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.1f | %.2f |\n", r.ms.total,
                  r.ms.totalQ3 - r.ms.totalQ1, r.ms.gradient, r.ms.pyramid, r.ms.visibility, r.ms.key, r.ms.shading,
                  r.ms.indirect, 1e6 * r.ms.total / r.cells(), r.ms.cores);
    }
    return md;
}

std::string fitsTable(const std::vector<Fit>& fits) {
    std::string md = "| time against | threads | fitted over | points | exponent |\n|---|---|---|---|---|\n";
    for (const Fit& f : fits) {
        const char* what = f.sweep == Sweep::Cells         ? "cells"
                           : f.sweep == Sweep::EnvAzimuths ? "environment azimuths m"
                                                           : "indirect azimuths";
        const std::string over = f.sweep == Sweep::Cells ? fmt("%.0f² .. %.0f²", std::sqrt(f.from), std::sqrt(f.to))
                                                         : fmt("%.0f .. %.0f", f.from, f.to);
        const std::string exponent = f.points >= 2 ? fmt("%.3f", f.exponent) : "- (fewer than 2 points)";
        md += fmt("| %s | %d | %s | %d | %s |\n", what, f.threads, over.c_str(), f.points, exponent.c_str());
    }
    return md;
}

// What the run was measured under: the load around it and its wall time.
struct RunNotes {
    std::string loadBefore, loadAfter;
    double seconds = 0.0;
};

std::string markdown(const std::vector<Row>& rows, const std::vector<Fit>& fits, const ScalingOptions& o,
                     const BenchContext& ctx, const RunNotes& notes) {
    const gi::GiSettings s = frameSettings(o);
    std::string md = "# GI frame time against cells and azimuths\n\n";
    md += "Machine: " + machineDescription() + "; load average " + notes.loadBefore + " before, " + notes.loadAfter +
          " after (other work on the same cores slows the frames, the 2-thread ones most).\n\n";
    md += fmt("Command: `%s` (%.0f s).\n\n", ctx.command.c_str(), notes.seconds);
    md +=
        fmt("Frames: the initial ground of builtinScene(\"erosion\", N, 1); the engine's default GI settings "
            "(gi/settings.h: m %d, k_v %d, o_v %d, %d indirect azimuths, blocker radiance) with one bounce and %dx "
            "sub-sampling, whole frames (incremental caching off); sun-and-sky environment plus one key light "
            "(azimuth 135, elevation 35, radius 5 degrees; 3 azimuths over its extent); uniform albedo 0.6 (the frames "
            "of the table1 suite). Median of %d frames after one warm-up frame (IQR: the interquartile range of those "
            "frames); the stage columns are medians "
            "of GiState::timings (ms; gradient and pyramid of the heights, environment visibility, key-light "
            "visibility, direct shading, indirect light with its radiance pyramid, scan and shading). cores: the "
            "process's CPU time over the wall time of the measured frames; below the thread count, other work had the "
            "cores.\n\n",
            s.visibility.azimuths, s.pyramid.levelsPerOctave, s.pyramid.levelOffset, s.indirect.azimuths, o.subsample,
            o.runs);
    md += "## Time against cells\n\n" + rowsTable(rows, Sweep::Cells);
    md +=
        fmt("\n## Time against azimuths (%d², %dx)\n\nEither the environment visibility's m swept (the indirect scan "
            "at its default azimuths) or the indirect scan's azimuths swept (m at its default).\n\n",
            o.azimuthSize, o.subsample);
    md += rowsTable(rows, Sweep::EnvAzimuths) + "\n" + rowsTable(rows, Sweep::IndirectAzimuths);
    md +=
        fmt("\n## Fitted exponents\n\ntime = a x^p, least squares on log time against log x. Against cells over the "
            "sizes from %d² up (below, the frame fits in the caches and fixed costs weigh more); against azimuths "
            "over every azimuth count measured. p = 1: time proportional to the cells (or azimuths).\n\n",
            o.fitFrom);
    md += fitsTable(fits) + "\n![GI frame time against cells and azimuths](scaling.png)\n";
    return md;
}

int runScaling(const ScalingOptions& o, const BenchContext& ctx) {
    RunNotes notes;
    notes.loadBefore = loadAverage();
    const auto start = std::chrono::steady_clock::now();
    std::fprintf(stderr, "scaling: time against cells\n");
    std::vector<Row> rows = sweepCells(o);
    std::fprintf(stderr, "scaling: time against azimuths\n");
    const std::vector<Row> az = sweepAzimuths(o);
    rows.insert(rows.end(), az.begin(), az.end());
    const std::vector<Fit> fits = fitAll(rows, o);
    notes.loadAfter = loadAverage();
    notes.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    writeResult(ctx.outDir, "scaling.md", markdown(rows, fits, o, ctx, notes));
    writeResult(ctx.outDir, "scaling.csv", csvText(rows, o.subsample));
    writeResult(ctx.outDir, "scaling_fit.csv", fitCsvText(fits));
    drawPlot(ctx, "scaling");
    return 0;
}

}  // namespace

Runner addScalingSuite(CLI::App& app, const BenchContext& ctx) {
    auto o = std::make_shared<ScalingOptions>();
    CLI::App* sub = app.add_subcommand(
        "scaling", "GI frame time against cells and against azimuths at 1 and 2 threads, with fitted exponents");
    addRunsOption(*sub, o->runs, "Frames per figure after a warm-up (median)");
    sub->add_option("--sizes", o->sizes, "Grid sizes N (N^2 cells) of the sweep against cells")
        ->check(CLI::Range(16, 8192))
        ->capture_default_str();
    sub->add_option("--subsample", o->subsample, "Sub-sampling of every frame")
        ->check(CLI::IsMember({1, 2, 4}))
        ->capture_default_str();
    sub->add_option("--azimuths", o->azimuths, "Azimuth counts of the sweeps against azimuths")
        ->check(CLI::Range(3, 4096))
        ->capture_default_str();
    sub->add_option("--azimuth-size", o->azimuthSize, "Grid size N of the sweeps against azimuths")
        ->check(CLI::Range(16, 8192))
        ->capture_default_str();
    sub->add_option("--threads", o->threads, "Thread counts")->check(CLI::Range(1, 256))->capture_default_str();
    sub->add_option("--fit-from", o->fitFrom, "Smallest size N the fit against cells uses")
        ->check(CLI::Range(1, 8192))
        ->capture_default_str();
    return [o, &ctx] { return runScaling(*o, ctx); };
}

}  // namespace terrain::bench
