// bench_gi: accuracy of the GI fast path against the ground truth, convergence
// in m / k_v / o_v, and time per frame, on the real DEMs of ../shared/data.
//
//   bench_gi [accuracy] [convergence] [timing] [explore] [--data DIR] [--out DIR] [--runs N]
//
// Writes bench/results/gi_*.md and gi_*.csv (and gi_speed_vs_error.png).
// Ground truths are cached beside the build (gi_reference_*.bin) because they
// take minutes.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <unistd.h>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "gi/frame.h"
#include "gi/reference.h"
#include "core/file_io.h"
#include "core/png_io.h"
#include "core/parallel.h"

using namespace terrain;
using namespace terrain::gi;

namespace {

using Clock = std::chrono::steady_clock;

struct Dem {
    std::string name;
    Grid heights;
    float cell = 1.0f;
};

struct ErrorStats {
    double rmse = 0.0, bias = 0.0, maxAbs = 0.0;
    long count = 0;
};

std::string gDataDir = "/work/shared/data";
std::string gOutDir = "bench/results";
int gRuns = 5;

Dem loadAlps() {
    Dem d;
    d.name = "alps-montblanc";
    d.heights = readPngHeightmap(gDataDir + "/alps-montblanc.png", (4810.0f - 454.0f) / 65535.0f, 454.0f);
    d.cell = 60000.0f / 647.0f;
    return d;
}

Dem loadPerdu() {
    Dem d;
    d.name = "mtperdu_20m";
    d.heights = readPngHeightmap(gDataDir + "/mtperdu_20m.png", 0.1f, 0.0f);
    d.cell = 20.0f;
    return d;
}

Dem crop(const Dem& src, int size, const std::string& tag) {
    Dem d;
    d.name = src.name + "-" + tag;
    d.cell = src.cell;
    const int x0 = (src.heights.nx - size) / 2, y0 = (src.heights.ny - size) / 2;
    d.heights.resize(size, size);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) d.heights(x, y) = src.heights(x0 + x, y0 + y);
    return d;
}

// Reference ambient on the interior (10 % border left out), every `stride`-th texel, cached.
Grid referenceAmbient(const Dem& d, int stride, int border) {
    const char* cacheDir = std::getenv("GI_CACHE_DIR");
    const std::string cache = std::string(cacheDir ? cacheDir : "/tmp") + "/gi_reference_" + d.name + "_s" + std::to_string(stride) + "_b" +
                              std::to_string(border) + ".bin";
    Grid g(d.heights.nx, d.heights.ny);
    {
        std::ifstream in(cache, std::ios::binary);
        if (in && in.read(reinterpret_cast<char*>(g.data()), static_cast<std::streamsize>(g.size() * sizeof(float)))) return g;
    }
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
    std::ofstream out(cache, std::ios::binary);
    out.write(reinterpret_cast<const char*>(rr.ambient.data()), static_cast<std::streamsize>(rr.ambient.size() * sizeof(float)));
    return rr.ambient;
}

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

// Median over gRuns frames after one warm-up frame.
Timing timeFrames(const Dem& d, const GiSettings& s, const GiLighting& light, GiState& st, int runs) {
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
    // median, or with GI_MIN set the minimum (robust to a busy machine while developing)
    const bool useMin = std::getenv("GI_MIN") != nullptr;
    auto med = [useMin](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return useMin ? v.front() : v[v.size() / 2];
    };
    return {med(tot), med(pyr), med(vis), med(key), med(sh)};
}

std::string settingsName(const GiSettings& s) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "m=%d k_v=%d o_v=%d %s %s peak=%.2f %dx", s.visibility.azimuths, s.pyramid.levelsPerOctave,
                  s.pyramid.levelOffset, s.visibility.interp == AzimuthInterp::Linear ? "linear" : "bspline",
                  s.visibility.blockingMax == BlockingMax::Samples ? "max=samples" : "max=bspline", s.pyramid.peakBlend,
                  s.subsample);
    return buf;
}

GiSettings paperSettings() { return GiSettings{}; }

GiSettings engineDefaults() { return engineGiSettings(); }

void writeFile(const std::string& name, const std::string& text) {
    const std::string path = gOutDir + "/" + name;
    writeFileAtomic(path, text);
    std::fprintf(stderr, "wrote %s\n", path.c_str());
}

std::string machine() {
    std::string cpu = "unknown CPU";
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("model name", 0) == 0) {
            cpu = line.substr(line.find(':') + 2);
            break;
        }
    return cpu + ", " + std::to_string(std::thread::hardware_concurrency()) + " hardware threads";
}

std::string buildFlags() {
    return std::string("GCC ") + __VERSION__ +
           ", CMAKE_BUILD_TYPE=Release (-O3 -DNDEBUG), -ffp-contract=off -fno-fast-math, baseline x86-64 (SSE2, no -march), "
           "4-wide GCC vector extensions in gi/";
}

std::string gCommand = "build-gi/bench_gi";

// ---------------------------------------------------------------------------
// accuracy: paper settings vs engine defaults on alps at true scale
// ---------------------------------------------------------------------------
struct Row {
    std::string label;
    GiSettings s;
    ErrorStats e;
    Timing t;
};

// quick: alps ambient error of the engine defaults and paper settings at 1x/2x/4x (for trying changes)
void quickAccuracy() {
    const Dem alps = loadAlps();
    const int border = alps.heights.nx / 10;
    const Grid ref = referenceAmbient(alps, 1, border);
    for (const char* which : {"paper", "engine"})
        for (int s : {1, 2, 4}) {
            GiSettings set = std::string(which) == "paper" ? GiSettings{} : engineGiSettings();
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

void runSettingsRows(const Dem& d, const Grid& ref, int border, std::vector<Row>& rows, int threads) {
    for (Row& r : rows) {
        GiState st;
        withThreads(threads, [&] {
            r.t = timeFrames(d, r.s, GiLighting{}, st, gRuns);
            return 0;
        });
        r.e = compare(st.shade.ambient, ref, 1, border);
        std::fprintf(stderr, "%-60s rmse %.4f bias %+.4f max %.3f  %.1f ms\n", (r.label + " " + settingsName(r.s)).c_str(),
                     r.e.rmse, r.e.bias, r.e.maxAbs, r.t.median);
    }
}

void accuracy() {
    const Dem alps = loadAlps();
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
    md += "Time: whole frame (gradient, pyramid, visibility, shading; uniform sky, no key light) with 2 threads, median of " +
          std::to_string(gRuns) + " after a warm-up.\n\nMachine: " + machine() + ". Build: " + buildFlags() + ".\n\nCommand: `" + gCommand + "` (from the repository root; reference cached in /tmp).\n\n";
    md += "| settings | RMSE | bias | max abs | ms/frame |\n|---|---|---|---|---|\n";
    std::string csv = "label,azimuths,levels_per_octave,level_offset,interp,blocking_max,peak_blend,subsample,rmse,bias,max_abs,ms\n";
    for (const Row& r : rows) {
        char buf[512];
        std::snprintf(buf, sizeof buf, "| %s: %s | %.4f | %+.4f | %.3f | %.1f |\n", r.label.c_str(), settingsName(r.s).c_str(),
                      r.e.rmse, r.e.bias, r.e.maxAbs, r.t.median);
        md += buf;
        std::snprintf(buf, sizeof buf, "%s,%d,%d,%d,%s,%s,%.2f,%d,%.5f,%.5f,%.4f,%.2f\n", r.label.c_str(), r.s.visibility.azimuths,
                      r.s.pyramid.levelsPerOctave, r.s.pyramid.levelOffset,
                      r.s.visibility.interp == AzimuthInterp::Linear ? "linear" : "bspline",
                      r.s.visibility.blockingMax == BlockingMax::Samples ? "samples" : "bspline", r.s.pyramid.peakBlend,
                      r.s.subsample, r.e.rmse, r.e.bias, r.e.maxAbs, r.t.median);
        csv += buf;
    }
    writeFile("gi_accuracy.md", md);
    writeFile("gi_accuracy.csv", csv);
}

// ---------------------------------------------------------------------------
// explore: many settings (used to choose the defaults)
// ---------------------------------------------------------------------------
void explore() {
    const Dem alps = loadAlps();
    const int border = alps.heights.nx / 10;
    const Grid ref = referenceAmbient(alps, 1, border);
    std::vector<Row> rows;
    for (int o : {2, 3, 4})
        for (float peak : {0.0f, 0.25f, 0.5f})
            for (BlockingMax bm : {BlockingMax::BsplineKnotsAndMidpoints, BlockingMax::Samples}) {
                GiSettings s;
                s.pyramid.levelOffset = o;
                s.pyramid.peakBlend = peak;
                s.visibility.blockingMax = bm;
                rows.push_back({"explore", s, {}, {}});
            }
    for (AzimuthInterp ip : {AzimuthInterp::Linear, AzimuthInterp::Bspline})
        for (int m : {24, 32, 48}) {
            GiSettings s = engineDefaults();
            s.visibility.interp = ip;
            s.visibility.azimuths = m;
            rows.push_back({"explore", s, {}, {}});
        }
    runSettingsRows(alps, ref, border, rows, 2);
    std::string csv = "azimuths,levels_per_octave,level_offset,interp,blocking_max,peak_blend,subsample,rmse,bias,max_abs,ms\n";
    for (const Row& r : rows) {
        char buf[256];
        std::snprintf(buf, sizeof buf, "%d,%d,%d,%s,%s,%.2f,%d,%.5f,%.5f,%.4f,%.2f\n", r.s.visibility.azimuths,
                      r.s.pyramid.levelsPerOctave, r.s.pyramid.levelOffset,
                      r.s.visibility.interp == AzimuthInterp::Linear ? "linear" : "bspline",
                      r.s.visibility.blockingMax == BlockingMax::Samples ? "samples" : "bspline", r.s.pyramid.peakBlend,
                      r.s.subsample, r.e.rmse, r.e.bias, r.e.maxAbs, r.t.median);
        csv += buf;
    }
    writeFile("gi_explore.csv", csv);
}

// ---------------------------------------------------------------------------
// convergence: error vs m, k_v, o_v and sub-sampling on a small terrain
// ---------------------------------------------------------------------------
void convergence() {
    const Dem alps = loadAlps();
    const Dem small = crop(alps, 256, "c256");
    const int border = small.heights.nx / 10;
    const Grid ref = referenceAmbient(small, 1, border);
    std::vector<Row> rows;
    auto base = [] {
        GiSettings s;
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
    md += "Terrain: alps-montblanc centre crop 256 x 256 at true scale (cell 92.74 m), interior only (25-texel border left out, " +
          std::to_string(rows[0].e.count) + " texels). Ambient RMSE / bias against gi/reference (256 azimuths, exact march "
          "of the bilinear field, exact elevation integrals). The m / k_v / o_v sweeps use the plain sample maximum (the "
          "B-spline maximum of Eq. 16 smooths the blocking-angle sequence and does not converge to the exact horizon); "
          "what remains at large m, k_v, o_v is the order-4 SH truncation of visibility (and m = 128 azimuth interpolation). "
          "Sub-sampling rows: the paper settings (m = 32, k_v = 4, o_v = 2, Eq. 16 maximum) and the engine defaults "
          "(o_v = 3, 25 % peak-keeping pyramid, sample maximum), 4x -> 2x -> 1x. Times: whole frame (uniform sky, no key "
          "light), 2 threads, median of " + std::to_string(gRuns) + ".\n\nMachine: " + machine() + ". Build: " + buildFlags() +
          ".\n\nCommand: `" + gCommand + "` (from the repository root; reference cached in /tmp).\n\n";
    md += "| sweep | settings | RMSE | bias | max abs | ms/frame |\n|---|---|---|---|---|---|\n";
    std::string csv = "sweep,azimuths,levels_per_octave,level_offset,blocking_max,peak_blend,subsample,rmse,bias,max_abs,ms\n";
    for (const Row& r : rows) {
        char buf[400];
        std::snprintf(buf, sizeof buf, "| %s | %s | %.4f | %+.4f | %.3f | %.1f |\n", r.label.c_str(), settingsName(r.s).c_str(),
                      r.e.rmse, r.e.bias, r.e.maxAbs, r.t.median);
        md += buf;
        std::snprintf(buf, sizeof buf, "%s,%d,%d,%d,%s,%.2f,%d,%.5f,%.5f,%.4f,%.2f\n", r.label.c_str(), r.s.visibility.azimuths,
                      r.s.pyramid.levelsPerOctave, r.s.pyramid.levelOffset,
                      r.s.visibility.blockingMax == BlockingMax::Samples ? "samples" : "bspline", r.s.pyramid.peakBlend,
                      r.s.subsample, r.e.rmse, r.e.bias, r.e.maxAbs, r.t.median);
        csv += buf;
    }
    writeFile("gi_convergence.md", md);
    writeFile("gi_convergence.csv", csv);
}

// ---------------------------------------------------------------------------
// speed-vs-error plot: rasterised here (lines, points, axes, a 5x7 font)
// ---------------------------------------------------------------------------
struct Canvas {
    int w, h;
    std::vector<std::uint8_t> px;
    Canvas(int width, int height) : w(width), h(height), px(static_cast<std::size_t>(width) * height * 3, 255) {}
    void set(int x, int y, const std::uint8_t c[3]) {
        if (x < 0 || y < 0 || x >= w || y >= h) return;
        for (int k = 0; k < 3; ++k) px[(static_cast<std::size_t>(y) * w + x) * 3 + k] = c[k];
    }
    void line(double x0, double y0, double x1, double y1, const std::uint8_t c[3], int thick = 1) {
        const int n = static_cast<int>(std::max(std::abs(x1 - x0), std::abs(y1 - y0))) + 1;
        for (int i = 0; i <= n; ++i) {
            const double t = static_cast<double>(i) / n;
            const int x = static_cast<int>(std::lround(x0 + t * (x1 - x0))), y = static_cast<int>(std::lround(y0 + t * (y1 - y0)));
            for (int dy = -(thick / 2); dy <= thick / 2; ++dy)
                for (int dx = -(thick / 2); dx <= thick / 2; ++dx) set(x + dx, y + dy, c);
        }
    }
    void dot(double x, double y, int r, const std::uint8_t c[3]) {
        for (int dy = -r; dy <= r; ++dy)
            for (int dx = -r; dx <= r; ++dx)
                if (dx * dx + dy * dy <= r * r) set(static_cast<int>(std::lround(x)) + dx, static_cast<int>(std::lround(y)) + dy, c);
    }
    void square(double x, double y, int r, const std::uint8_t c[3]) {
        for (int dy = -r; dy <= r; ++dy)
            for (int dx = -r; dx <= r; ++dx) set(static_cast<int>(std::lround(x)) + dx, static_cast<int>(std::lround(y)) + dy, c);
    }
    // 5x7 glyphs, each row a 5-bit mask (bit 4 = leftmost), scaled by `scale`
    void text(int x, int y, const std::string& str, const std::uint8_t c[3], int scale = 2) {
        for (char ch : str) {
            const std::uint8_t* g = glyph(ch);
            for (int r = 0; r < 7; ++r)
                for (int col = 0; col < 5; ++col)
                    if (g[r] & (16 >> col))
                        for (int sy = 0; sy < scale; ++sy)
                            for (int sx = 0; sx < scale; ++sx) set(x + col * scale + sx, y + r * scale + sy, c);
            x += 6 * scale;
        }
    }
    static const std::uint8_t* glyph(char ch) {
        static const struct { char c; std::uint8_t rows[7]; } font[] = {
            {'0', {14, 17, 19, 21, 25, 17, 14}}, {'1', {4, 12, 4, 4, 4, 4, 14}},   {'2', {14, 17, 1, 2, 4, 8, 31}},
            {'3', {30, 1, 1, 14, 1, 1, 30}},     {'4', {2, 6, 10, 18, 31, 2, 2}},  {'5', {31, 16, 30, 1, 1, 17, 14}},
            {'6', {6, 8, 16, 30, 17, 17, 14}},   {'7', {31, 1, 2, 4, 8, 8, 8}},    {'8', {14, 17, 17, 14, 17, 17, 14}},
            {'9', {14, 17, 17, 15, 1, 2, 12}},   {'.', {0, 0, 0, 0, 0, 12, 12}},   {'x', {0, 0, 17, 10, 4, 10, 17}},
            {'m', {0, 0, 26, 21, 21, 21, 21}},   {'s', {0, 0, 15, 16, 14, 1, 30}}, {'R', {30, 17, 17, 30, 20, 18, 17}},
            {'M', {17, 27, 21, 21, 17, 17, 17}}, {'S', {15, 16, 16, 14, 1, 1, 30}}, {'E', {31, 16, 16, 30, 16, 16, 31}},
            {'p', {0, 0, 30, 17, 30, 16, 16}},   {'a', {0, 0, 14, 1, 15, 17, 15}}, {'e', {0, 0, 14, 17, 31, 16, 14}},
            {'r', {0, 0, 22, 25, 16, 16, 16}},   {'n', {0, 0, 22, 25, 17, 17, 17}}, {'g', {0, 0, 15, 17, 15, 1, 14}},
            {'i', {4, 0, 12, 4, 4, 4, 14}},      {'o', {0, 0, 14, 17, 17, 17, 14}}, {'f', {6, 9, 8, 28, 8, 8, 8}},
            {'t', {8, 8, 28, 8, 8, 9, 6}},       {'l', {12, 4, 4, 4, 4, 4, 14}},   {'h', {16, 16, 22, 25, 17, 17, 17}},
            {'d', {1, 1, 13, 19, 17, 19, 13}},   {'c', {0, 0, 14, 16, 16, 17, 14}}, {'u', {0, 0, 17, 17, 17, 19, 13}},
            {'b', {16, 16, 22, 25, 17, 17, 30}}, {'v', {0, 0, 17, 17, 17, 10, 4}},  {'w', {0, 0, 17, 17, 21, 21, 10}},
            {'k', {16, 16, 18, 20, 24, 20, 18}}, {'y', {0, 0, 17, 17, 15, 1, 14}},  {'T', {31, 4, 4, 4, 4, 4, 4}},
            {'(', {2, 4, 8, 8, 8, 4, 2}},        {')', {8, 4, 2, 2, 2, 4, 8}},     {',', {0, 0, 0, 0, 12, 4, 8}},
            {'-', {0, 0, 0, 31, 0, 0, 0}},       {'=', {0, 0, 31, 0, 31, 0, 0}},   {'/', {1, 1, 2, 4, 8, 16, 16}},
            {':', {0, 12, 12, 0, 12, 12, 0}},    {'^', {4, 10, 17, 0, 0, 0, 0}},   {' ', {0, 0, 0, 0, 0, 0, 0}},
            {'G', {14, 17, 16, 23, 17, 17, 15}}, {'I', {14, 4, 4, 4, 4, 4, 14}},   {'q', {0, 0, 15, 17, 15, 1, 1}},
        };
        static const std::uint8_t unknown[7] = {31, 17, 17, 17, 17, 17, 31};
        for (const auto& f : font)
            if (f.c == ch) return f.rows;
        return unknown;
    }
};

struct PlotPoint {
    int size, subsample, threads;
    std::string settings;
    double ms, rmse;
};

void speedErrorPlot(const std::vector<PlotPoint>& pts, const std::string& file) {
    const int W = 1000, H = 680, left = 110, right = 250, top = 60, bottom = 90;
    Canvas c(W, H);
    const std::uint8_t black[3] = {0, 0, 0}, grey[3] = {215, 215, 215};
    double msLo = 1e30, msHi = 0.0, eHi = 0.0;
    for (const PlotPoint& p : pts)
        if (p.threads == 2) {
            msLo = std::min(msLo, p.ms);
            msHi = std::max(msHi, p.ms);
            eHi = std::max(eHi, p.rmse);
        }
    const double lx0 = std::floor(std::log10(msLo)), lx1 = std::ceil(std::log10(msHi));
    const double eTop = std::ceil(eHi / 0.01) * 0.01;
    auto X = [&](double ms) { return left + (std::log10(ms) - lx0) / (lx1 - lx0) * (W - left - right); };
    auto Y = [&](double e) { return H - bottom - e / eTop * (H - top - bottom); };
    // grid and axes
    for (double d = lx0; d <= lx1 + 1e-9; d += 1.0)
        for (int k = 1; k < 10; ++k) {
            const double v = std::pow(10.0, d) * k;
            if (std::log10(v) > lx1 + 1e-9) break;
            c.line(X(v), top, X(v), H - bottom, grey);
            if (k == 1 || (lx1 - lx0 <= 3.0 ? (k == 2 || k == 5) : k == 3)) {  // sparser labels over many decades
                char b[32];
                std::snprintf(b, sizeof b, "%g", v);
                c.text(static_cast<int>(X(v)) - 6 * static_cast<int>(std::string(b).size()), H - bottom + 10, b, black);
            }
        }
    for (double e = 0.0; e <= eTop + 1e-9; e += 0.005) {
        c.line(left, Y(e), W - right, Y(e), grey);
        char b[32];
        std::snprintf(b, sizeof b, "%.3f", e);
        c.text(left - 80, static_cast<int>(Y(e)) - 7, b, black);
    }
    c.line(left, top, left, H - bottom, black, 2);
    c.line(left, H - bottom, W - right, H - bottom, black, 2);
    c.text(left + 120, H - 40, "ms per frame (2 threads, log scale)", black);
    c.text(20, 20, "ambient RMSE vs ground truth", black);
    c.text(left + 330, 20, "GI frame: speed vs error", black);
    // one polyline per (size, settings) through 4x -> 2x -> 1x; 15 ms target line
    const std::uint8_t colours[3][3] = {{200, 40, 40}, {40, 110, 200}, {30, 150, 60}};
    const int sizes[3] = {256, 512, 1024};
    const std::uint8_t target[3] = {150, 150, 150};
    c.line(X(15.0), top, X(15.0), H - bottom, target, 1);
    c.text(static_cast<int>(X(15.0)) + 4, top + 4, "15 ms target", target);
    int legendY = top + 10;
    for (int si = 0; si < 3; ++si)
        for (const char* which : {"paper", "engine"}) {
            std::vector<const PlotPoint*> line;
            for (int sub : {4, 2, 1})
                for (const PlotPoint& p : pts)
                    if (p.threads == 2 && p.size == sizes[si] && p.settings == which && p.subsample == sub) line.push_back(&p);
            const bool paper = std::string(which) == "paper";
            for (std::size_t i = 0; i + 1 < line.size(); ++i)
                c.line(X(line[i]->ms), Y(line[i]->rmse), X(line[i + 1]->ms), Y(line[i + 1]->rmse), colours[si], paper ? 1 : 3);
            for (const PlotPoint* p : line) {
                if (paper) c.square(X(p->ms), Y(p->rmse), 4, colours[si]);
                else c.dot(X(p->ms), Y(p->rmse), 5, colours[si]);
                char b[8];
                std::snprintf(b, sizeof b, "%dx", p->subsample);
                c.text(static_cast<int>(X(p->ms)) + 7, static_cast<int>(Y(p->rmse)) - 16, b, colours[si]);
            }
            const int lx = W - right + 20;
            if (paper) c.square(lx + 6, legendY + 7, 4, colours[si]);
            else c.dot(lx + 6, legendY + 7, 5, colours[si]);
            c.text(lx + 20, legendY, std::to_string(sizes[si]) + "^2 " + which, colours[si]);
            legendY += 24;
        }
    c.text(W - right + 20, legendY + 10, "squares: paper", black);
    c.text(W - right + 20, legendY + 34, "dots: engine", black);
    writePngRgb(file, W, H, c.px);
    std::fprintf(stderr, "wrote %s\n", file.c_str());
}

// ---------------------------------------------------------------------------
// timing: 256^2, 512^2, 1024^2 x 1x/2x/4x x 1/2 threads, one env + one key light
// ---------------------------------------------------------------------------
void timing() {
    const Dem alps = loadAlps();
    const Dem perdu = loadPerdu();
    struct Size { Dem dem; std::string source; };
    std::vector<Size> sizes;
    sizes.push_back({crop(alps, 256, "c256"), "alps c256"});
    sizes.push_back({crop(alps, 512, "c512"), "alps c512"});
    sizes.push_back({crop(perdu, 1024, "c1024"), "mtperdu c1024"});
    GiLighting light;
    light.environment = sunSkyLight();
    KeyLight key;
    key.azimuthDeg = 135.0f;
    key.elevationDeg = 30.0f;
    key.radiusDeg = 4.0f;
    light.keys.push_back(key);
    std::string md = "# GI time per frame\n\n";
    md += "Frame = gradient + pyramid + environment visibility + key-light visibility + direct shading (Lambert, RGB + ambient "
          "map), one sun-and-sky environment light (m azimuths) and one key light (3 azimuths over its extent), as "
          "`terrain gi --frames N --time` runs it. Median of " + std::to_string(gRuns) +
          " frames after a warm-up (best of 3 repeats, below); stage columns are medians too (ms).\n\n"
          "DEMs (centre crops at true scale, no resampling): 256^2 and 512^2 = ../shared/data/alps-montblanc.png (cell 92.74 m), "
          "1024^2 = ../shared/data/mtperdu_20m.png (cell 20 m).\n\n"
          "Error: ambient map (normal-weighted sky-view factor) RMSE / bias against gi/reference (256 azimuths, exact march) "
          "over the interior (10 % border left out); at 1024^2 over every 4th texel in x and y of the interior (the "
          "reference is computed and cached only there). The error does not depend on the thread count.\n\n"
          "Settings: paper = m 32, k_v 4, o_v 2, Eq. 16 B-spline maximum; engine = the engine defaults (o_v 3, 25 % "
          "peak-keeping pyramid, sample maximum). pyramid = gradient + pyramid.\n\nThe machine is shared with other work (2 vCPUs): "
          "each row is measured 3 times (median of " + std::to_string(gRuns) + " frames each) and the lowest of the 3 medians is "
          "reported with its stage medians; a repeat during which other processes used more than 5 % of a core is discarded "
          "and re-done (other load = other processes' CPU time over the kept repeat, from /proc/stat, in cores). Load on the "
          "other vCPU of a shared physical core does not show in /proc/stat, so single rows can still be noisy.\n\nMachine: " +
          machine() + ". Build: " +
          buildFlags() + ".\n\nCommand: `" + gCommand + "` (from the repository root; references cached in /tmp).\n\n";
    md += "| DEM | size | sub | settings | threads | ms/frame | pyramid | visibility | key light | shading | RMSE | bias | other load |\n";
    md += "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    std::string csv = "dem,size,subsample,settings,threads,ms,pyramid_ms,visibility_ms,key_ms,shading_ms,rmse,bias,other_load\n";
    std::vector<PlotPoint> pts;
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
                    Timing t;
                    // The machine is shared (2 vCPUs, other people's builds): each row is
                    // measured 3 times (median of gRuns frames each) and the lowest median
                    // kept; a repeat during which other processes used more than 5 % of a
                    // core (/proc/stat minus our own CPU time) is re-done, up to 6 extra times.
                    double otherLoad = 0.0;
                    Timing best;
                    best.median = 1e30;
                    for (int good = 0, attempt = 0; good < 3 && attempt < 9; ++attempt) {
                        const double busy0 = machineBusySeconds(), own0 = processCpuSeconds();
                        const auto w0 = Clock::now();
                        withThreads(threads, [&] {
                            t = timeFrames(sz.dem, set, light, st, gRuns);
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
                    t = best;
                    const ErrorStats e = compare(st.shade.ambient, ref, stride, border);
                    char buf[600];
                    std::snprintf(buf, sizeof buf, "| %s | %d | %dx | %s | %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.4f | %+.4f | %.2f |\n",
                                  sz.source.c_str(), n, s, which, threads, t.median, t.pyramid, t.visibility, t.key, t.shading,
                                  e.rmse, e.bias, otherLoad);
                    md += buf;
                    std::snprintf(buf, sizeof buf, "%s,%d,%d,%s,%d,%.2f,%.2f,%.2f,%.2f,%.2f,%.5f,%.5f,%.3f\n", sz.dem.name.c_str(), n, s,
                                  which, threads, t.median, t.pyramid, t.visibility, t.key, t.shading, e.rmse, e.bias, otherLoad);
                    csv += buf;
                    pts.push_back({n, s, threads, which, t.median, e.rmse});
                    std::fprintf(stderr, "%s %d %dx %s %dT: %.1f ms (rmse %.4f)\n", sz.dem.name.c_str(), n, s, which, threads,
                                 t.median, e.rmse);
                }
    }
    md += "\n![speed vs error](gi_speed_error.png)\n";
    writeFile("gi_timing.md", md);
    writeFile("gi_timing.csv", csv);
    speedErrorPlot(pts, gOutDir + "/gi_speed_error.png");
}

// plot only, from an existing gi_timing.csv
void plotFromCsv() {
    std::ifstream in(gOutDir + "/gi_timing.csv");
    std::string line;
    std::getline(in, line);
    std::vector<PlotPoint> pts;
    while (std::getline(in, line)) {
        std::vector<std::string> f;
        std::size_t a = 0;
        for (std::size_t b; (b = line.find(',', a)) != std::string::npos; a = b + 1) f.push_back(line.substr(a, b - a));
        f.push_back(line.substr(a));
        if (f.size() < 12) continue;
        pts.push_back({std::atoi(f[1].c_str()), std::atoi(f[2].c_str()), std::atoi(f[4].c_str()), f[3], std::atof(f[5].c_str()),
                       std::atof(f[10].c_str())});
    }
    speedErrorPlot(pts, gOutDir + "/gi_speed_error.png");
}

// ---------------------------------------------------------------------------
// stages: per-stage times of the target frames (quick check while optimising)
// ---------------------------------------------------------------------------
void stages() {
    const Dem alps = loadAlps();
    GiLighting light;
    light.environment = sunSkyLight();
    KeyLight key;
    key.azimuthDeg = 135.0f;
    key.elevationDeg = 30.0f;
    key.radiusDeg = 4.0f;
    light.keys.push_back(key);
    struct Case { const Dem* dem; int s; const char* which; };
    const Dem c512 = crop(alps, 512, "c512");
    int caseIndex = -1;
    for (const Case& c : {Case{&c512, 2, "engine"}, Case{&c512, 2, "paper"}, Case{&alps, 1, "engine"}, Case{&alps, 1, "paper"}}) {
        ++caseIndex;
        if (std::getenv("GI_CASE") && std::atoi(std::getenv("GI_CASE")) != caseIndex) continue;  // one case only
        GiSettings set = std::string(c.which) == "paper" ? paperSettings() : engineDefaults();
        set.subsample = c.s;
        GiState st;
        Timing t;
        const int threads = std::getenv("GI_THREADS") ? std::atoi(std::getenv("GI_THREADS")) : 2;
        timespec c0{}, c1{};
        withThreads(threads, [&] {
            t = timeFrames(*c.dem, set, light, st, gRuns);
            clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
            runGiFrame(c.dem->heights.cview(), c.dem->cell, light, set, st);
            clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
            return 0;
        });
        const double cpu = (c1.tv_sec - c0.tv_sec) * 1e3 + (c1.tv_nsec - c0.tv_nsec) * 1e-6;
        std::printf("%-22s %dx %-6s %dT: %6.1f ms, cpu %6.1f ms (pyramid+grad %.1f, visibility %.1f, key %.1f, shading %.1f)\n",
                    c.dem->name.c_str(), c.s, c.which, threads, t.median, cpu, t.pyramid, t.visibility, t.key, t.shading);
        // GI_DUMP=write stores the outputs, GI_DUMP=compare reports the largest change against them
        if (const char* dump = std::getenv("GI_DUMP")) {
            const std::string file = "/tmp/gi_stage_" + c.dem->name + "_" + std::to_string(c.s) + c.which + ".bin";
            std::vector<const Grid*> grids = {&st.shade.ambient, &st.shade.rgb[0], &st.shade.rgb[1], &st.shade.rgb[2]};
            if (std::string(dump) == "write") {
                std::ofstream out(file, std::ios::binary);
                for (const Grid* g : grids) out.write(reinterpret_cast<const char*>(g->data()), static_cast<std::streamsize>(g->size() * 4));
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
                std::printf("    vs stored: ambient max %.3g mean %.3g; rgb max %.3g %.3g %.3g\n", maxd[0], sumd[0], maxd[1], maxd[2], maxd[3]);
            }
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

void cpuStages() {
    const Dem alps = loadAlps();
    const Dem c512 = crop(alps, 512, "c512");
    GiLighting light;
    light.environment = sunSkyLight();
    KeyLight key;
    key.azimuthDeg = 135.0f;
    key.elevationDeg = 30.0f;
    key.radiusDeg = 4.0f;
    light.keys.push_back(key);
    struct Case { const Dem* dem; int s; const char* which; };
    int caseIndex = -1;
    for (const Case& c : {Case{&c512, 2, "engine"}, Case{&c512, 2, "paper"}, Case{&alps, 1, "engine"}}) {
        ++caseIndex;
        if (std::getenv("GI_CASE") && std::atoi(std::getenv("GI_CASE")) != caseIndex) continue;
        GiSettings set = std::string(c.which) == "paper" ? paperSettings() : engineDefaults();
        set.subsample = c.s;
        withThreads(1, [&] {
            GiState st;
            runGiFrame(c.dem->heights.cview(), c.dem->cell, light, set, st);
            double best[5] = {1e30, 1e30, 1e30, 1e30, 1e30};
            for (int r = 0; r < gRuns; ++r) {
                double t0 = threadCpuMs();
                computeGradient(c.dem->heights.cview(), c.dem->cell, st.gradX, st.gradY);
                buildHeightPyramid(c.dem->heights.cview(), c.dem->cell, set.subsample, set.pyramid, st.pyramid);
                double t1 = threadCpuMs();
                VisibilityTarget env;
                env.op = &st.envOperator;
                computeVisibility(st.pyramid, st.gradX.cview(), st.gradY.cview(), set.visibility, env, st.visibilityState, st.envVisibility);
                double t2 = threadCpuMs();
                runGiFrame(c.dem->heights.cview(), c.dem->cell, light, set, st);
                double t3 = threadCpuMs();
                best[0] = std::min(best[0], t1 - t0);
                best[1] = std::min(best[1], t2 - t1);
                best[2] = std::min(best[2], t3 - t2);
                best[3] = std::min(best[3], st.timings.keyVisibility);
                best[4] = std::min(best[4], st.timings.shading);
            }
            std::printf("%-22s %dx %-6s cpu: grad+pyramid %.1f  env visibility %.1f  frame %.1f  (wall key %.1f shading %.1f)\n",
                        c.dem->name.c_str(), c.s, c.which, best[0], best[1], best[2], best[3], best[4]);
            return 0;
        });
    }
}

}  // namespace

int main(int argc, char** argv) {
    std::vector<std::string> modes;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--data" && i + 1 < argc) gDataDir = argv[++i];
        else if (a == "--out" && i + 1 < argc) gOutDir = argv[++i];
        else if (a == "--runs" && i + 1 < argc) gRuns = std::max(1, std::atoi(argv[++i]));
        else modes.push_back(a);
    }
    for (int i = 1; i < argc; ++i) gCommand += std::string(" ") + argv[i];
    if (modes.empty()) modes = {"accuracy", "convergence", "timing"};
    try {
        for (const std::string& m : modes) {
            if (m == "accuracy") accuracy();
            else if (m == "convergence") convergence();
            else if (m == "timing") timing();
            else if (m == "explore") explore();
            else if (m == "stages") stages();
            else if (m == "quick") quickAccuracy();
            else if (m == "plot") plotFromCsv();
            else if (m == "cpu") cpuStages();
            else {
                std::fprintf(stderr, "bench_gi: unknown mode %s\n", m.c_str());
                return 2;
            }
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_gi: error: %s\n", e.what());
        return 1;
    }
    return 0;
}
