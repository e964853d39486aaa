// `terrain_bench table1`: the paper's Table 1 (Nowrouzezahrai & Snyder 2009)
// on this machine: GI frame time by size x sub-sampling x bounces, with and
// without shading amortisation, the GI's memory, and the paper's GTX 285
// figures beside ours; the error of each figure against the exact reference
// where one can be afforded; where the memory goes; and the animated erosion
// scene (simulation + GI) in frames per second. Writes table1.{md,csv} and
// the plot table1.{png,svg}.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <malloc.h>

#include "bench/indirect_frame.h"
#include "bench/suites.h"
#include "core/parallel.h"
#include "engine/pipeline.h"
#include "sim/scene.h"

namespace terrain::bench {
namespace {
using namespace terrain::gi;
using Clock = std::chrono::steady_clock;

struct Table1Options {
    std::vector<int> sizes{256, 512, 1024, 2048};
    std::vector<int> subsamples{1, 2, 4};
    int maxBounces = 3;
    int runs = 7;     // frames per median, after one warm-up
    int repeats = 2;  // the lowest of this many medians is reported (shared machine)
    std::vector<int> errorSizes{256, 512};
    std::string cache;  // folder of the cached references
    int animatedFrames = 30;
};

// The paper's Table 1 (GTX 285): frames per second for 1, 2 and 3 bounces,
// without and with shading amortisation, and the GI memory in MB.
struct PaperRow {
    double fps[3], fpsAmortised[3], memoryMB;
};
std::optional<PaperRow> paperRow(int size, int s) {
    static const std::map<std::pair<int, int>, PaperRow> rows = {
        {{256, 1}, {{49.5, 44, 40}, {100, 86, 79}, 17.4}},     {{256, 2}, {{125, 107.7, 101}, {230, 194, 176}, 4.5}},
        {{256, 4}, {{229, 198, 185}, {363, 303, 276}, 1.65}},  {{512, 1}, {{11.6, 10.5, 10}, {24, 22, 20}, 76}},
        {{512, 2}, {{35.5, 32, 30}, {67, 60, 56}, 20}},        {{512, 4}, {{73, 65.6, 62}, {124, 110, 104}, 7.1}},
        {{1024, 1}, {{2.7, 2.4, 2.2}, {5, 5, 4}, 336}},        {{1024, 2}, {{8.3, 7.6, 7.1}, {16, 14, 14}, 88}},
        {{1024, 4}, {{18.9, 17.2, 16.4}, {32, 30, 28}, 29.5}},
    };
    const auto it = rows.find({size, s});
    if (it == rows.end()) return std::nullopt;
    return it->second;
}

// Bytes the allocator holds for the program (every arena, mmapped blocks too).
double heapMB() {
    const struct mallinfo2 m = mallinfo2();
    return static_cast<double>(m.uordblks + m.hblkhd) / (1024.0 * 1024.0);
}

struct RowTimes {
    Spread ms{1e30}, msAmortised{1e30};
    double msIndirect = 0.0, memoryMB = 0.0;
};

// Frames of one configuration on one GiState after one warm-up: plain, each
// frame's time; amortised (cheap and expensive frames alternate), the mean of
// each pair of frames. Their median and quartiles.
Spread timeFrames(const Dem& d, const AlbedoMap& a, const GiSettings& g, int runs, GiState& st, double* indirectMs) {
    const GiLighting light = sunSkyAndBenchKey();
    std::vector<double> t, ti;
    const int frames = g.indirect.amortise ? (runs + 1) / 2 * 2 : runs;
    for (int f = 0; f <= frames; ++f) {
        st.geometryChanged = f == 0;
        const auto t0 = Clock::now();
        runGiFrame(d.heights.cview(), d.cell, light, g, st, &a);
        if (f == 0) continue;
        t.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
        ti.push_back(st.timings.indirect);
    }
    if (indirectMs) *indirectMs = median(ti);
    if (!g.indirect.amortise) return spreadOf(t);
    std::vector<double> pairs;
    for (std::size_t i = 0; i + 1 < t.size(); i += 2) pairs.push_back(0.5 * (t[i] + t[i + 1]));
    return spreadOf(pairs);
}

RowTimes timeRow(const Dem& d, const AlbedoMap& a, int s, int b, const Table1Options& o) {
    RowTimes r;
    withThreads(2, [&] {
        for (int rep = 0; rep < o.repeats; ++rep) {
            GiSettings g = indirectFrameSettings(s, b, false);
            const double before = heapMB();
            auto st = std::make_unique<GiState>();
            double indirect = 0.0;
            const Spread ms = timeFrames(d, a, g, o.runs, *st, &indirect);
            if (ms.median < r.ms.median) {
                r.ms = ms;
                r.msIndirect = indirect;
            }
            r.memoryMB = heapMB() - before;
            st.reset();
            g.indirect.amortise = true;
            GiState sa;
            const Spread amortised = timeFrames(d, a, g, o.runs, sa, nullptr);
            if (amortised.median < r.msAmortised.median) r.msAmortised = amortised;
        }
    });
    return r;
}

// The paper's figure in ms and our ratio to it ("-" without one).
void paperColumns(const std::optional<PaperRow>& p, int b, const RowTimes& r, std::string& md, std::string& csv) {
    if (!p) {
        md += " - | - | - | - |";
        csv += ",,,,";
        return;
    }
    const double ms = 1000.0 / p->fps[b - 1], msA = 1000.0 / p->fpsAmortised[b - 1];
    const double ours = r.ms.median, oursA = r.msAmortised.median;
    md += fmt(" %.1f |", ms) + fmt(" %.2f |", ours / ms) + fmt(" %.1f |", msA) + fmt(" %.2f |", oursA / msA);
    csv += fmt(",%.2f", ms) + fmt(",%.3f", ours / ms) + fmt(",%.2f", msA) + fmt(",%.3f", oursA / msA);
}

class Table1Suite {
public:
    Table1Suite(const Table1Options& o, const BenchContext& ctx) : o_(o), ctx_(ctx) {}

    int run() {
        std::string md = header(), csv =
                                       "size,subsample,bounces,ms,ms_amortised,indirect_ms,memory_mb,paper_memory_mb,"
                                       "indirect_rel_rmse,total_rel_rmse,paper_ms,ratio,paper_ms_amortised,ratio_"
                                       "amortised,ms_q1,ms_q3,ms_amortised_q1,ms_amortised_q3\n";
        md +=
            "| size | sub | bounces | ms / frame | IQR | ms amortised | IQR | indirect ms | memory MB | paper MB | "
            "indirect error | total error | paper ms | ratio | paper ms amortised | ratio amortised |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        for (int n : o_.sizes) sizeRows(n, md, csv);
        md += memoryBreakdown();
        md += animatedErosion();
        writeResult(ctx_.outDir, "table1.md", md);
        writeResult(ctx_.outDir, "table1.csv", csv);
        drawPlot(ctx_, "table1");
        return 0;
    }

private:
    const Table1Options& o_;
    const BenchContext& ctx_;

    std::string header() const {
        return "# The paper's Table 1 on this machine\n\nMachine: " + machineDescription() + ". 2 threads. Command: `" +
               ctx_.command + "`.\n\nFrame: builtinScene(\"erosion\", N, 1) initial ground; engine settings (" +
               indirectSettingsSummary() +
               "), sun-and-sky environment + one key light, albedo 0.6, Lambert; whole frames (no incremental "
               "caching). ms / frame: median of " +
               std::to_string(o_.runs) + " frames after one warm-up, the lowest of " + std::to_string(o_.repeats) +
               " such medians (the machine is a shared virtual machine); IQR: the interquartile range of the frames "
               "of that median (CSV: ms_q1, ms_q3). Amortised: static geometry, frames alternate direct and indirect "
               "updates (Section 7); the median of the means of consecutive pairs (one frame of each kind), with "
               "their IQR. Memory (our MB: 2^20 bytes): what the "
               "allocator holds for the GI state after the frames (every buffer the frame keeps, measured by "
               "mallinfo2, not estimated). Errors: indirect and total relative RMSE (interior) against the exact "
               "reference of an eroded frame of the same size (after 2000 ticks), where one is computed "
               "(sizes " +
               sizesText(o_.errorSizes) +
               "). Paper: GTX 285, Table 1 of Nowrouzezahrai & Snyder 2009 (k_v = k_u = 4, m = 32, 8x multi-sampling "
               "included in their frame); ratio = our ms / the paper's ms (below 1: faster).\n\n";
    }

    static std::string sizesText(const std::vector<int>& v) {
        std::string t;
        for (int n : v) t += (t.empty() ? "" : ", ") + std::to_string(n) + "^2";
        return t.empty() ? "none" : t;
    }

    bool hasErrors(int n) const {
        for (int e : o_.errorSizes)
            if (e == n) return true;
        return false;
    }

    void sizeRows(int n, std::string& md, std::string& csv) const {
        const Dem d = erodedScene(n, 0);
        const AlbedoMap a = uniformAlbedo(n, n, kIndirectFrameAlbedo);
        std::optional<Dem> eroded;
        std::optional<GiReference> ref;
        if (hasErrors(n)) {
            eroded = erodedScene(n, 2000);
            ref = cachedReference(o_.cache, *eroded, sunSkyAndBenchKey(), a, o_.maxBounces, n <= 256 ? 2048 : 1024);
        }
        for (int s : o_.subsamples)
            for (int b = 1; b <= o_.maxBounces; ++b) {
                std::fprintf(stderr, "table1: %d^2 %dx %d bounce(s) ...\n", n, s, b);
                const RowTimes r = timeRow(d, a, s, b, o_);
                const std::optional<PaperRow> p = paperRow(n, s);
                std::string errI = "-", errT = "-";
                if (ref) {
                    GiState st;
                    withThreads(2, [&] {
                        runGiFrame(eroded->heights.cview(), eroded->cell, sunSkyAndBenchKey(),
                                   indirectFrameSettings(s, b, false), st, &a);
                    });
                    const IndirectErrors e = indirectErrors(st, *ref, b);
                    errI = fmt("%.4f", e.indirect);
                    errT = fmt("%.4f", e.total);
                }
                const std::string paperMem = p ? fmt("%.1f", p->memoryMB) : "-";
                md += "| " + std::to_string(n) + "^2 | " + std::to_string(s) + "x | " + std::to_string(b) + " |" +
                      fmt(" %.1f |", r.ms.median) + fmt(" %.1f |", r.ms.iqr()) + fmt(" %.1f |", r.msAmortised.median) +
                      fmt(" %.1f |", r.msAmortised.iqr()) + fmt(" %.1f |", r.msIndirect) + fmt(" %.1f |", r.memoryMB) +
                      " " + paperMem + " | " + errI + " | " + errT + " |";
                csv += std::to_string(n) + "," + std::to_string(s) + "," + std::to_string(b) +
                       fmt(",%.2f", r.ms.median) + fmt(",%.2f", r.msAmortised.median) + fmt(",%.2f", r.msIndirect) +
                       fmt(",%.1f", r.memoryMB) + "," + (p ? paperMem : "") + "," + (ref ? errI : "") + "," +
                       (ref ? errT : "");
                paperColumns(p, b, r, md, csv);
                md += "\n";
                csv += fmt(",%.2f,%.2f,%.2f,%.2f\n", r.ms.q1, r.ms.q3, r.msAmortised.q1, r.msAmortised.q3);
                std::fprintf(stderr, "  %.1f ms (IQR %.1f), amortised %.1f ms, %.1f MB\n", r.ms.median, r.ms.iqr(),
                             r.msAmortised.median, r.memoryMB);
            }
    }

    std::string memoryBreakdown() const;
    std::string animatedErosion() const;
};

// ---- where the memory goes ------------------------------------------------------
template <class T, class A>
double mbOf(const std::vector<T, A>& v) {
    return static_cast<double>(v.capacity() * sizeof(T)) / (1024.0 * 1024.0);
}
double mbOf(const Grid& g) { return mbOf(g.v); }
double levelsMB(const HeightPyramid& p) {
    double m = 0.0;
    for (const PaddedField& f : p.levels) m += mbOf(f.v);
    return m;
}
double pyramidMB(const HeightPyramid& p) {
    double m = mbOf(p.rawPhase) + mbOf(p.rowTmp) + levelsMB(p);
    for (const Grid& g : p.meanOctaves) m += mbOf(g);
    for (const Grid& g : p.maxOctaves) m += mbOf(g);
    for (const PaddedField& f : p.synth) m += mbOf(f.v);
    return m;
}
double shadeMB(const ShadeMaps& s) {
    double m = mbOf(s.ambient) + mbOf(s.skyBelow) + mbOf(s.skyRising) + mbOf(s.incident) + mbOf(s.incidentWindow) +
               mbOf(s.rowScratch);
    for (const Grid& g : s.rgb) m += mbOf(g);
    return m;
}

// The largest buffers of a frame's state by part; "other" is what the
// allocator holds beyond them (scratch, tables, caches).
std::vector<std::pair<std::string, double>> memoryParts(const GiState& st) {
    const IndirectState& in = st.indirect;
    double radiance = 0.0, radianceLevels = 0.0, key = 0.0, outputs = 0.0, blocker = 0.0, scan = 0.0;
    for (const HeightPyramid& p : in.radiance.fields) {
        radiance += pyramidMB(p);
        radianceLevels += levelsMB(p);
    }
    for (const VisibilityField& v : st.keyVisibility) key += mbOf(v.sh) + mbOf(v.maxSlope);
    for (const ShadeMaps& s : in.bounceShade) outputs += shadeMB(s);
    for (std::size_t c = 0; c < 3; ++c) outputs += mbOf(in.indirect[c]) + mbOf(in.total[c]);
    const BlockerRadianceState& br = in.blocker;
    blocker = mbOf(br.farSlope) + mbOf(br.heights) + mbOf(br.occlusion) + mbOf(br.receiverOcclusion) +
              mbOf(br.scratch) + mbOf(br.taps) + mbOf(br.cols);
    for (const std::vector<float>& e : br.receiverShade) blocker += mbOf(e);
    for (const IndirectScratch& s : in.blocks)
        scan += mbOf(s.result) + mbOf(s.irradiance) + mbOf(s.state) + mbOf(s.gx) + mbOf(s.gy) + mbOf(s.h0) +
                mbOf(s.margin) + mbOf(s.groupSteps) + mbOf(s.active);
    return {{"gradient (full resolution)", mbOf(st.gradX) + mbOf(st.gradY)},
            {"height pyramid: levels at the receiver grid", levelsMB(st.pyramid)},
            {"height pyramid: octaves, syntheses, raw phases", pyramidMB(st.pyramid) - levelsMB(st.pyramid)},
            {"environment V: SH planes", mbOf(st.envVisibility.sh)},
            {"environment V: horizons per azimuth", mbOf(st.envVisibility.maxSlope)},
            {"key light V", key},
            {"direct shading (RGB, ambient, sky parts, incident SH)", shadeMB(st.shade)},
            {"radiance pyramids: levels", radianceLevels},
            {"radiance pyramids: octaves, syntheses, raw phases", radiance - radianceLevels},
            {"blocker radiance (horizons, occlusion, receivers' E)", blocker},
            {"indirect: bounce exit radiance, indirect and total RGB", outputs},
            {"indirect scan scratch", scan}};
}

std::string Table1Suite::memoryBreakdown() const {
    std::string md =
        "\n## Where the memory goes\n\nMB per part of the GI state after a frame (one bounce), the largest buffers "
        "counted by capacity; other = what the allocator holds beyond them.\n\n";
    std::vector<std::pair<int, int>> cases;
    for (int n : o_.sizes)
        for (int s : o_.subsamples)
            if ((n == 512 && s == 2) || (n == 1024 && s == 1) || (n == 2048 && s == 2)) cases.emplace_back(n, s);
    if (cases.empty()) return "";
    std::vector<std::vector<std::pair<std::string, double>>> parts;
    std::vector<double> totals;
    for (auto [n, s] : cases) {
        const Dem d = erodedScene(n, 0);
        const AlbedoMap a = uniformAlbedo(n, n, kIndirectFrameAlbedo);
        const double before = heapMB();
        auto st = std::make_unique<GiState>();
        withThreads(2, [&] {
            runGiFrame(d.heights.cview(), d.cell, sunSkyAndBenchKey(), indirectFrameSettings(s, 1, false), *st, &a);
        });
        totals.push_back(heapMB() - before);
        parts.push_back(memoryParts(*st));
    }
    md += "| part |";
    for (auto [n, s] : cases) md += " " + std::to_string(n) + "^2 " + std::to_string(s) + "x |";
    md += "\n|---|";
    for (std::size_t i = 0; i < cases.size(); ++i) md += "---|";
    md += "\n";
    std::vector<double> counted(cases.size(), 0.0);
    for (std::size_t k = 0; k < parts[0].size(); ++k) {
        md += "| " + parts[0][k].first + " |";
        for (std::size_t i = 0; i < cases.size(); ++i) {
            md += fmt(" %.1f |", parts[i][k].second);
            counted[i] += parts[i][k].second;
        }
        md += "\n";
    }
    md += "| other |";
    for (std::size_t i = 0; i < cases.size(); ++i) md += fmt(" %.1f |", totals[i] - counted[i]);
    md += "\n| **total (allocator)** |";
    for (std::size_t i = 0; i < cases.size(); ++i) md += fmt(" **%.1f** |", totals[i]);
    return md + "\n";
}

// ---- the animated erosion scene: simulation + GI ----------------------------------
std::string Table1Suite::animatedErosion() const {
    if (o_.animatedFrames <= 0) return "";
    std::string md =
        "\n## Animated erosion at 512^2: simulation + GI\n\nbuiltinScene(\"erosion\", 512, 1) through the "
        "engine's frame pipeline (engine/pipeline.h) at the scene's pacing: the ticks of a frame, then the GI "
        "(global lighting, 2x, one bounce) and the per-texel frame data, no rendering; 2 threads; " +
        std::to_string(o_.animatedFrames) +
        " frames after the spin-up and one frame; medians, and the interquartile range of the whole frame.\n\n| GI "
        "frames | ticks / frame | sim ms | GI + frame data ms | ms / frame | IQR | frames / s |\n"
        "|---|---|---|---|---|---|---|\n";
    for (bool incremental : {false, true}) {
        engine::PipelineSettings ps;
        ps.lighting = engine::LightingMode::Global;
        ps.gi.subsample = 2;
        ps.gi.indirect.bounces = 1;
        ps.gi.incremental = incremental;
        std::vector<double> sim, total;
        int ticks = 0;
        withThreads(2, [&] {
            engine::FramePipeline p(builtinScene("erosion", 512, 1), ps);
            ticks = p.ticksPerFrame();
            for (int f = 0; f <= o_.animatedFrames + 1; ++f) {
                const auto t0 = Clock::now();
                p.advance();
                const auto t1 = Clock::now();
                p.light();
                const auto t2 = Clock::now();
                if (f < 2) continue;  // the spin-up, then the first lit frame
                sim.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
                total.push_back(std::chrono::duration<double, std::milli>(t2 - t0).count());
            }
        });
        const Spread whole = spreadOf(total);
        const double ms = whole.median, msSim = median(sim);
        std::fprintf(stderr, "table1: animated erosion 512^2, %s GI: %.1f ms / frame\n",
                     incremental ? "incremental" : "full", ms);
        md += std::string("| ") + (incremental ? "incremental (engine default, tolerance 0.02)" : "full recompute") +
              " | " + std::to_string(ticks) + " |" + fmt(" %.1f |", msSim) + fmt(" %.1f |", ms - msSim) +
              fmt(" %.1f |", ms) + fmt(" %.1f |", whole.iqr()) + fmt(" %.1f |", 1000.0 / ms) + "\n";
    }
    return md;
}

}  // namespace

Runner addTable1Suite(CLI::App& app, const BenchContext& ctx) {
    auto o = std::make_shared<Table1Options>();
    o->cache = defaultReferenceCacheDir();
    CLI::App* sub = app.add_subcommand(
        "table1",
        "The paper's Table 1 on this machine: frame time, amortised time and memory by size, sub-sampling "
        "and bounces, beside the paper's GTX 285 figures, with errors; animated erosion fps");
    addRunsOption(*sub, o->runs, "Frames per median after one warm-up");
    sub->add_option("--repeats", o->repeats, "Medians per figure, the lowest reported (a shared machine)")
        ->check(CLI::Range(1, 20))
        ->capture_default_str();
    sub->add_option("--sizes", o->sizes, "Grid sizes (n for n x n)")
        ->check(CLI::Range(16, 4096))
        ->capture_default_str();
    sub->add_option("--subsamples", o->subsamples, "Sub-samplings")
        ->check(CLI::IsMember({1, 2, 4}))
        ->capture_default_str();
    sub->add_option("--bounces", o->maxBounces, "Bounces 1..N")->check(CLI::Range(1, 3))->capture_default_str();
    sub->add_option("--error-sizes", o->errorSizes, "Sizes whose rows carry errors against the exact reference")
        ->capture_default_str();
    sub->add_option("--cache", o->cache, "Folder of the cached references (empty: no cache)")->capture_default_str();
    sub->add_option("--animated-frames", o->animatedFrames, "Frames of the animated erosion run (0: none)")
        ->check(CLI::Range(0, 10000))
        ->capture_default_str();
    return [o, &ctx] { return Table1Suite(*o, ctx).run(); };
}

}  // namespace terrain::bench
